// SPDX-License-Identifier: Apache-2.0
// Tests of the glTF / textured-material path (render/gltf.h, render/pbr_material.h,
// render/texture.h) and of the asset scenes in scenes/assets-*.json (docs/assets.md):
//   - every asset scene loads (a missing asset is a failure, never a skip) and renders finite pixels,
//   - the glTF material mapping: alpha = roughness^2, metallic 1 is the conductor, metallic 0 the
//     diffuse + F0 0.04 specular mix, transmission the dielectric, clearcoat the coated lobe, and a
//     textured base colour splits the metal exactly,
//   - texture look-up, wrap modes and KHR_texture_transform on a tiny generated glTF,
//   - the normal-map frame (tangent along +u, +Y of the map towards v = 0),
//   - broken glTF files (Debian assimp-testmodels and generated ones) fail with one clean line,
//   - every strategy converges to the same per-object means on an asset scene (z-test).
#include <gtest/gtest.h>


#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "test_util.h"
#include "envpis/image_file.h"
#include "render/gltf.h"
#include "render/render.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;

#ifdef ENVPIS_SOURCE_DIR
const fs::path kRepo = ENVPIS_SOURCE_DIR;
#else
const fs::path kRepo = fs::path(ENVPIS_TEST_DATA).parent_path().parent_path();  // tests/data -> repo
#endif
const std::string kModels = "/usr/share/assimp/models/glTF2";

std::vector<fs::path> asset_scenes() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(kRepo / "scenes"))
    if (e.path().filename().string().rfind("assets-", 0) == 0 && e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::shared_ptr<const EnvironmentMap> small_sky() {
  static const auto env = [] {
    SkyOptions o;
    o.width = 128;
    o.height = 64;
    o.sun_elevation = 30.0f;
    o.sun_azimuth = 250.0f;
    o.sun_radius = 6.0f;
    o.sun_radiance = 25.0f;
    return std::make_shared<const EnvironmentMap>(make_procedural_sky(o));
  }();
  return env;
}

TEST(AssetScenes, EveryAssetSceneLoadsWithItsAssetsAndRendersFinitePixels) {
  const auto scenes = asset_scenes();
  ASSERT_GE(scenes.size(), 3u) << "expected at least three scenes/assets-*.json";
  // No skip: a missing asset (assimp-testmodels, scripts/fetch-assets.sh) fails here.
  for (const fs::path& p : scenes) {
    SCOPED_TRACE(p.string());
    Scene s;
    try {
      s = load_scene_file(p.string(), small_sky());
    } catch (const Error& e) {
      FAIL() << e.what() << " (install the assets: scripts/install-deps.sh or scripts/fetch-assets.sh)";
    }
    EXPECT_GE(s.objects().size(), 3u);
    RenderOptions o;
    o.strategy = Strategy::Product;
    o.spp = 2;
    o.width = 48;
    o.height = 27;
    const RenderResult r = render(s, o);
    EXPECT_EQ(r.nonfinite_pixels, 0u);
    std::size_t covered = 0;
    for (int id : r.object_id) covered += id >= 0;
    EXPECT_GT(covered, r.object_id.size() / 4) << "the camera should see the objects";
  }
}

TEST(AssetScenes, TogetherTheySpanTheRequiredMaterials) {
  bool textured_roughness = false, normal_map = false, transmissive = false, coated = false;
  for (const fs::path& p : asset_scenes()) {
    const Scene s = load_scene_file(p.string(), small_sky());
    for (int i = 0; i < s.material_count(); ++i) {
      const SceneMaterial& m = s.material(i);
      transmissive = transmissive || m.transmissive;
      if (m.pbr) {
        textured_roughness = textured_roughness || bool(m.pbr->textures().metallic_roughness);
        normal_map = normal_map || m.pbr->has_normal_map();
        coated = coated || m.pbr->params().clearcoat > 0;
      }
    }
  }
  EXPECT_TRUE(textured_roughness);
  EXPECT_TRUE(normal_map);
  EXPECT_TRUE(transmissive);
  EXPECT_TRUE(coated);
}

// ---- material mapping ----

const Vec3 kWo = normalize(Vec3{0.3f, -0.2f, 0.9f});
std::vector<Vec3> test_directions() {
  return {normalize(Vec3{-0.3f, 0.2f, 0.9f}), normalize(Vec3{-0.25f, 0.1f, 0.95f}), normalize(Vec3{0.5f, 0.5f, 0.6f}),
          normalize(Vec3{-0.8f, 0.1f, 0.3f}), normalize(Vec3{0.1f, -0.1f, -0.9f})};
}

Material single(std::shared_ptr<const Lobe> l) {
  Material m;
  m.add(std::move(l), 1.0f);
  return m;
}

void expect_same_bsdf(const Material& a, const Material& b, float tol = 1e-5f) {
  for (Vec3 wi : test_directions()) {
    const Rgb fa = a.eval(kWo, wi), fb = b.eval(kWo, wi);
    EXPECT_NEAR(fa.r, fb.r, tol * (1 + std::fabs(fb.r))) << "wi " << wi.x << " " << wi.y << " " << wi.z;
    EXPECT_NEAR(fa.g, fb.g, tol * (1 + std::fabs(fb.g)));
    EXPECT_NEAR(fa.b, fb.b, tol * (1 + std::fabs(fb.b)));
  }
}

Material assembled(const PbrParams& p, PbrTextures t = {}, Point2 uv = {0.5f, 0.5f}) {
  PbrMaterial pm(p, std::move(t));
  Material m;
  pm.assemble(uv, &m);
  return m;
}

TEST(PbrMaterial, MetallicOneIsTheConductorWithAlphaRoughnessSquared) {
  PbrParams p;
  p.base_color = {0.9f, 0.6f, 0.3f};
  p.metallic = 1;
  p.roughness = 0.5f;
  const Material m = assembled(p);
  EXPECT_EQ(m.lobe_count(), 1u);
  expect_same_bsdf(m, single(make_conductor_reflectance(0.25f, p.base_color)));
  BsdfProxy proxy;
  m.fill_proxy(proxy, kWo);
  EXPECT_NEAR(proxy.alpha_reflection, 0.25f, 1e-6f);
  EXPECT_EQ(proxy.diffuse, 0.0f);
}

TEST(PbrMaterial, MetallicZeroIsDiffusePlusASpecularLobeWithF0Of004) {
  PbrParams p;
  p.base_color = {0.2f, 0.5f, 0.8f};
  p.metallic = 0;
  p.roughness = 0.3f;
  Material ref;
  ref.add(make_conductor_reflectance(0.09f, {0.04f, 0.04f, 0.04f}), 1.0f);
  ref.add(make_lambert({1, 1, 1}), p.base_color * 0.96f);
  expect_same_bsdf(assembled(p), ref);
  // A half-metal is the average of the two.
  p.metallic = 0.5f;
  Material half;
  half.add(make_conductor_reflectance(0.09f, p.base_color), 0.5f);
  half.add(make_conductor_reflectance(0.09f, {0.04f, 0.04f, 0.04f}), 0.5f);
  half.add(make_lambert({1, 1, 1}), p.base_color * 0.48f);
  expect_same_bsdf(assembled(p), half);
}

TEST(PbrMaterial, TransmissionIsTheDielectricAndClearcoatTheCoatedLobe) {
  PbrParams glass;
  glass.metallic = 0;
  glass.roughness = 0.2f;
  glass.transmission = 1;
  glass.ior = 1.33f;
  EXPECT_TRUE(PbrMaterial(glass, {}).transmissive());
  expect_same_bsdf(assembled(glass), single(make_dielectric(0.04f, 1.33f)));

  PbrParams coat;
  coat.base_color = {0.5f, 0.1f, 0.1f};
  coat.metallic = 0;
  coat.clearcoat = 1;
  coat.clearcoat_roughness = 0.3f;
  EXPECT_FALSE(PbrMaterial(coat, {}).transmissive());
  expect_same_bsdf(assembled(coat), single(make_coated_diffuse(coat.base_color, 0.09f, 1.5f)));
}

std::shared_ptr<const Texture> solid(Rgba c) {
  return std::make_shared<const Texture>(1, 1, std::vector<float>{c.r, c.g, c.b, c.a});
}

TEST(PbrMaterial, ATexturedBaseColourSplitsTheMetalExactly) {
  PbrParams p;
  p.metallic = 1;
  p.roughness = 0.4f;
  PbrTextures t;
  t.base_color.texture = solid({0.9f, 0.5f, 0.1f, 1});
  expect_same_bsdf(assembled(p, t), single(make_conductor_reflectance(0.16f, {0.9f, 0.5f, 0.1f})));
}

TEST(PbrMaterial, TexturedRoughnessUsesTheNearestLevelAndMetallicTheBlueChannel) {
  PbrParams p;
  p.base_color = {0.8f, 0.8f, 0.8f};
  p.metallic = 1;
  p.roughness = 1;
  PbrTextures t;
  const float r = 10.0f / (PbrMaterial::kRoughnessLevels - 1);  // exactly a level
  t.metallic_roughness.texture = solid({0, r, 1, 1});
  const Material m = assembled(p, t);
  BsdfProxy proxy;
  m.fill_proxy(proxy, kWo);
  EXPECT_NEAR(proxy.alpha_reflection, r * r, 1e-6f);
  t.metallic_roughness.texture = solid({0, r, 0, 1});  // metallic 0: a dielectric
  BsdfProxy dielectric;
  assembled(p, t).fill_proxy(dielectric, kWo);
  EXPECT_GT(dielectric.diffuse, 0.0f);
}

TEST(PbrMaterial, RejectsOutOfRangeFactors) {
  PbrParams p;
  p.roughness = 1.5f;
  EXPECT_THROW(PbrMaterial(p, {}), Error);
  p.roughness = 0.5f;
  p.ior = 0.5f;
  EXPECT_THROW(PbrMaterial(p, {}), Error);
}

// ---- textures and a generated glTF ----

TEST(Texture, BilinearWrapModesAndTheKhrTextureTransformExample) {
  // 2 x 2: red, green / blue, white (rows top to bottom).
  const Texture tex(2, 2, {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 1});
  auto near = [](Rgba a, Rgb b) { return std::fabs(a.r - b.r) < 1e-6f && std::fabs(a.g - b.g) < 1e-6f && std::fabs(a.b - b.b) < 1e-6f; };
  EXPECT_TRUE(near(tex.bilinear({0.25f, 0.25f}, TextureWrap::Repeat, TextureWrap::Repeat), {1, 0, 0}));
  EXPECT_TRUE(near(tex.bilinear({0.75f, 0.75f}, TextureWrap::Repeat, TextureWrap::Repeat), {1, 1, 1}));
  EXPECT_TRUE(near(tex.bilinear({0.5f, 0.25f}, TextureWrap::Repeat, TextureWrap::Repeat), {0.5f, 0.5f, 0}));
  EXPECT_TRUE(near(tex.bilinear({1.25f, -0.75f}, TextureWrap::Repeat, TextureWrap::Repeat), {1, 0, 0}));
  EXPECT_TRUE(near(tex.bilinear({-0.25f, 0.25f}, TextureWrap::Mirror, TextureWrap::Clamp), {1, 0, 0}));
  EXPECT_TRUE(near(tex.bilinear({0.0f, 0.25f}, TextureWrap::Repeat, TextureWrap::Clamp), {0.5f, 0.5f, 0}));
  EXPECT_TRUE(near(tex.bilinear({0.0f, 0.25f}, TextureWrap::Clamp, TextureWrap::Clamp), {1, 0, 0}));
  // The extension's example: offset (0, 1), rotation 90 degrees, scale 0.5 maps [0, 1]^2 onto the
  // lower-left quadrant (u in [0, 0.5], v in [0.5, 1]).
  UvTransform t;
  t.offset = {0, 1};
  t.rotation = kPi / 2;
  t.scale = {0.5f, 0.5f};
  for (Point2 uv : {Point2{0, 0}, Point2{1, 0}, Point2{0, 1}, Point2{1, 1}, Point2{0.3f, 0.7f}}) {
    const Point2 q = t.apply(uv);
    EXPECT_GE(q.x, -1e-6f);
    EXPECT_LE(q.x, 0.5f + 1e-6f);
    EXPECT_GE(q.y, 0.5f - 1e-6f);
    EXPECT_LE(q.y, 1.0f + 1e-6f);
  }
}

std::string base64(const std::vector<std::uint8_t>& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    unsigned v = unsigned(in[i]) << 16 | (i + 1 < in.size() ? unsigned(in[i + 1]) << 8 : 0) | (i + 2 < in.size() ? in[i + 2] : 0);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[v & 63] : '=';
  }
  return out;
}

void write_png(const fs::path& path, int w, int h, const std::vector<std::uint8_t>& rgb) {
  std::vector<float> px(rgb.begin(), rgb.end());
  for (float& v : px) v /= 255.0f;
  write_image_file(path.string(), w, h, 3, px.data());  // 8-bit: rounds back to the same codes
}

/// A 2 x 2 quad facing glTF's +Y (the renderer's +Z), UVs like make_quad, with a base-colour texture
/// (red green / blue white, KHR_texture_transform `transform_json`) and a 1 x 1 normal map `normal`.
fs::path write_test_gltf(const fs::path& dir, const std::string& name, const std::string& transform_json,
                         std::array<std::uint8_t, 3> normal) {
  write_png(dir / "colors.png", 2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
  write_png(dir / (name + "-normal.png"), 1, 1, {normal[0], normal[1], normal[2]});
  std::vector<std::uint8_t> bin;
  auto put = [&bin](const void* p, std::size_t n) { bin.insert(bin.end(), (const std::uint8_t*)p, (const std::uint8_t*)p + n); };
  const float pos[12] = {-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1};
  const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};
  const std::uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
  put(pos, sizeof pos);
  put(uv, sizeof uv);
  put(idx, sizeof idx);
  std::ofstream f(dir / (name + ".gltf"));
  f << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "materials": [{"name": "tex", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.5,
     "baseColorTexture": {"index": 0)" << transform_json << R"(}}, "normalTexture": {"index": 1}}],
  "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
  "samplers": [{"wrapS": 10497, "wrapT": 10497}],
  "images": [{"uri": "colors.png"}, {"uri": ")" << name << R"(-normal.png"}],
  "buffers": [{"byteLength": )" << bin.size() << R"(, "uri": "data:application/octet-stream;base64,)" << base64(bin) << R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]})";
  return dir / (name + ".gltf");
}

/// The hit of a ray straight down at (x, y) on a scene made of the glTF file.
SurfaceHit hit_at(const Scene& s, float x, float y) {
  SurfaceHit h;
  EXPECT_TRUE(s.intersect({{x, y, 5}, {0, 0, -1}, kInfinity}, &h));
  return h;
}

TEST(Gltf, TextureLookUpFollowsTheUvsAndKhrTextureTransform) {
  const test::TempDir tmp;
  const fs::path plain = write_test_gltf(tmp.path, "plain", "", {128, 128, 255});
  const fs::path shifted = write_test_gltf(tmp.path, "shifted", R"(, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0]}})", {128, 128, 255});
  const Scene a = load_scene_file(plain.string(), small_sky()), b = load_scene_file(shifted.string(), small_sky());
  ASSERT_EQ(a.objects().size(), 1u);
  const SceneMaterial& ma = a.material(a.objects()[0].material);
  const SceneMaterial& mb = b.material(b.objects()[0].material);
  ASSERT_TRUE(ma.textured());
  // (-0.5, 0.5) is u = 0.25, v = 0.25: the top-left (red) texel; +X is +u, +Y is towards v = 0.
  const SurfaceHit h = hit_at(a, -0.5f, 0.5f);
  EXPECT_NEAR(h.uv.x, 0.25f, 1e-5f);
  EXPECT_NEAR(h.uv.y, 0.25f, 1e-5f);
  const Rgb red = ma.pbr->textures().base_color.sample(h.uv).rgb();
  EXPECT_NEAR(red.r, 1, 1e-4f);
  EXPECT_NEAR(red.g, 0, 1e-4f);
  const Rgb white = ma.pbr->textures().base_color.sample(hit_at(a, 0.5f, -0.5f).uv).rgb();
  EXPECT_NEAR(white.r + white.g + white.b, 3, 1e-3f);
  // The offset moves the look-up half a texture to the right: green at the same point.
  const Rgb green = mb.pbr->textures().base_color.sample(h.uv).rgb();
  EXPECT_NEAR(green.r, 0, 1e-4f);
  EXPECT_NEAR(green.g, 1, 1e-4f);
  // The assembled BSDF's diffuse lobe carries the texel's colour.
  Material m;
  ma.pbr->assemble(h.uv, &m);
  const Rgb f = m.eval({0, 0, 1}, normalize(Vec3{0.8f, 0, 0.6f}));  // far from the specular peak
  EXPECT_GT(f.r, 10 * f.g);
}

TEST(Gltf, NormalMapFrameHasTheTangentAlongUAndGreenTowardsVZero) {
  // Tangent-space normal (0.36, 0.48, 0.8) -> RGB (0.68, 0.74, 0.9).
  const test::TempDir tmp;
  const fs::path file = write_test_gltf(tmp.path, "bent", "", {173, 189, 230});
  const Scene s = load_scene_file(file.string(), small_sky());
  const SceneMaterial& m = s.material(s.objects()[0].material);
  ASSERT_TRUE(m.pbr->has_normal_map());
  const SurfaceHit h = hit_at(s, 0.2f, 0.3f);
  const Vec3 n = m.pbr->normal_mapped(h.uv, h.ns, h.dpdu, h.bitangent_sign);
  EXPECT_NEAR(n.x, 0.36f, 0.01f);
  EXPECT_NEAR(n.y, 0.48f, 0.01f);
  EXPECT_NEAR(n.z, 0.80f, 0.01f);
  EXPECT_NEAR(length(n), 1.0f, 1e-5f);
}

TEST(Gltf, CamerasComeFromTheFile) {
  const GltfModel model = load_gltf(kModels + "/cameras/Cameras.gltf");
  ASSERT_TRUE(model.camera.has_value());
  EXPECT_GT(model.camera->vfov_degrees, 1.0f);
  EXPECT_LT(model.camera->vfov_degrees, 179.0f);
  EXPECT_GT(length(model.camera->to - model.camera->from), 0.0f);
  // And in a JSON scene with "use_camera", moved by the object's transform.
  const test::TempDir tmp;
  const fs::path& dir = tmp.path;
  std::ofstream(dir / "cam.json") << R"({"objects": [{"type": "gltf", "file": ")" << kModels
                                  << R"(/cameras/Cameras.gltf", "use_camera": true, "translate": [0, 0, 10]}]})";
  const Scene s = load_scene_file((dir / "cam.json").string(), small_sky());
  EXPECT_NEAR(s.camera().from.z, model.camera->from.z + 10, 1e-4f);
}

// ---- broken files ----

TEST(Gltf, BrokenFilesFailWithOneCleanLineThroughTheCommand) {
  std::vector<std::string> files;
  for (const char* f : {"MissingBin/BoxTextured.gltf", "RecursiveNodes/RecursiveNodes.gltf",
                        "SchemaFailures/sceneWrongType.gltf", "TestNoRootNode/NoScene.gltf",
                        "TestNoRootNode/SceneWithoutNodes.gltf", "BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
                        "IndexOutOfRange/AllIndicesOutOfRange.gltf", "issue_3269/texcoord_crash.gltf",
                        "wrongTypes/badArray.gltf", "wrongTypes/badExtension.gltf", "wrongTypes/badNumber.gltf",
                        "wrongTypes/badObject.gltf", "wrongTypes/badString.gltf", "wrongTypes/badUint.gltf"}) {
    ASSERT_TRUE(fs::exists(kModels + "/" + f)) << "missing " << kModels << "/" << f << " (Debian assimp-testmodels)";
    files.push_back(kModels + "/" + f);
  }
  const test::TempDir tmp;
  const fs::path& dir = tmp.path;
  // fuzz_gltf's finds and guards: a PNG texture with a bad IDAT checksum (libpng's message has two
  // lines), a glTF 1.0 file (never handed to assimp's other readers), an image URI naming /dev/zero.
  {
    fs::create_directories(dir / "crc");
    for (const char* f : {"BoxTextured.gltf", "BoxTextured0.bin", "CesiumLogoFlat.png"})
      fs::copy_file(kModels + "/BoxTextured-glTF/" + f, dir / "crc" / f, fs::copy_options::overwrite_existing);
    std::ifstream in(dir / "crc/CesiumLogoFlat.png", std::ios::binary);
    std::string png((std::istreambuf_iterator<char>(in)), {});
    in.close();
    const std::size_t idat = png.find("IDAT");
    ASSERT_NE(idat, std::string::npos);
    const std::size_t len = (std::size_t(std::uint8_t(png[idat - 4])) << 24) | (std::size_t(std::uint8_t(png[idat - 3])) << 16) |
                            (std::size_t(std::uint8_t(png[idat - 2])) << 8) | std::size_t(std::uint8_t(png[idat - 1]));
    png[idat + 4 + len] = char(png[idat + 4 + len] ^ 0x55);  // the chunk's CRC
    std::ofstream(dir / "crc/CesiumLogoFlat.png", std::ios::binary) << png;
    files.push_back((dir / "crc/BoxTextured.gltf").string());
    const std::string v1 = kModels + "/../glTF/TwoBoxes/TwoBoxes.gltf";
    ASSERT_TRUE(fs::exists(v1)) << "missing " << v1 << " (Debian assimp-testmodels)";
    files.push_back(v1);
    const fs::path zero = write_test_gltf(tmp.path, "devzero", "", {128, 128, 255});
    std::ifstream zin(zero);
    std::string text((std::istreambuf_iterator<char>(zin)), {});
    zin.close();
    text.replace(text.find("colors.png"), 10, "/dev/zero");
    std::ofstream(zero) << text;
    files.push_back(zero.string());
  }
  // Generated: a truncated GLB, a GLB with a bad version, garbage, an image that is not one.
  {
    std::ifstream in(kModels + "/BoxTextured-glTF-Binary/BoxTextured.glb", std::ios::binary);
    std::vector<char> b((std::istreambuf_iterator<char>(in)), {});
    ASSERT_GT(b.size(), 400u);
    std::ofstream(dir / "truncated.glb", std::ios::binary).write(b.data(), 300);
    b[4] = 7;
    std::ofstream(dir / "version.glb", std::ios::binary).write(b.data(), std::streamsize(b.size()));
    std::ofstream(dir / "garbage.gltf") << "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [";
    const fs::path good = write_test_gltf(tmp.path, "badimage", "", {128, 128, 255});
    std::ofstream(dir / "colors.png") << "not a png";
    files.push_back(good.string());
  }
  for (const char* f : {"truncated.glb", "version.glb", "garbage.gltf"}) files.push_back((dir / f).string());
  std::vector<std::string> args;
  for (const std::string& f : files)
    args.push_back("render --quiet --spp 1 --width 8 --height 8 --scene " + test::shell_quote(f) + " --out " +
                   test::shell_quote((dir / "out.exr").string()));
  const auto results = test::run_envpis_all(args, 2, 60);
  for (std::size_t i = 0; i < files.size(); ++i) {
    SCOPED_TRACE(files[i]);
    EXPECT_EQ(results[i].code, 1) << results[i].output;  // not 0, not a crash (-1), not a hang (124)
    const std::string line = test::line_starting(results[i].output, "envpis render: error: ");
    EXPECT_FALSE(line.empty()) << results[i].output;
    EXPECT_NE(line.find(fs::path(files[i]).filename().string()), std::string::npos) << line;
    EXPECT_EQ(std::count(results[i].output.begin(), results[i].output.end(), '\n'), 1) << results[i].output;
  }
}

TEST(Gltf, SceneFilesNameTheFieldAndMissingAssetsFail) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path;
  std::ofstream(dir / "broken.json") << R"({"camera": {"from": [0, -5, 1], "to": [0, 0, 0]}, "objects": [
    {"type": "gltf", "file": "${ASSIMP_MODELS}/glTF2/wrongTypes/badNumber.gltf"}]})";
  try {
    load_scene_file((dir / "broken.json").string(), small_sky());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0].file"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "unknown.json") << R"({"camera": {"from": [0, -5, 1], "to": [0, 0, 0]}, "objects": [
    {"type": "gltf", "file": "${NOPE}/x.glb"}]})";
  EXPECT_THROW(load_scene_file((dir / "unknown.json").string(), small_sky()), Error);
  // An asset directory without the assets: a clean error naming the missing file.
  ::setenv("ENVPIS_ASSETS", "/nonexistent-envpis-assets", 1);
  try {
    load_scene_file((kRepo / "scenes/assets-bunny.json").string(), small_sky());
    ADD_FAILURE() << "no error without the assets";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-envpis-assets/"), std::string::npos) << e.what();
  }
  ::unsetenv("ENVPIS_ASSETS");
}

// ---- convergence on an asset scene ----

// Every strategy's per-object means agree with a reference of another strategy on the clear-coat
// scene (textured base colours and roughness, normal maps, coated lobes), with the path integrator.
// Not `env`: the scene's coats have roughness 0.03 (GGX alpha 9e-4, clamped to 1e-3), which light
// samples alone meet only by chance; its estimate is unbiased but far too heavy-tailed for a z-test
// at any affordable sample count (test_render.cpp tests env on fig1).
TEST(AssetConvergence, EveryStrategyMatchesTheReferencePerObject) {
  const Scene scene = load_scene_file((kRepo / "scenes/assets-clearcoat.json").string(), small_sky());
  auto options = [](Strategy s, int spp, std::uint64_t seed) {
    RenderOptions o;
    o.strategy = s;
    o.spp = spp;
    o.seed = seed;
    o.width = 64;
    o.height = 36;
    o.max_depth = 4;
    o.oracle.resolution = 8;
    return o;
  };
  const int n = static_cast<int>(scene.objects().size());
  const auto ref_mis = object_means(render(scene, options(Strategy::Mis, 512, 1000)), n);
  const auto ref_product = object_means(render(scene, options(Strategy::Product, 512, 2000)), n);
  std::vector<int> objects;  // objects with enough pixels for a trustworthy variance
  for (int i = 0; i < n; ++i)
    if (ref_mis[i].pixels >= 12) objects.push_back(i);
  ASSERT_GE(objects.size(), 8u);
  std::vector<Strategy> strategies;
  for (Strategy s : all_strategies())
    if (s != Strategy::Env) strategies.push_back(s);
  const int tests = static_cast<int>((strategies.size() + 5) * objects.size());
  const double alpha = 1e-3 / tests;
  double z_max = 0;
  for (double lo = 0, hi = 10, i = 0; i < 100; ++i, z_max = lo) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  // Every strategy, then product's variants: without the product cache, and with the product
  // distribution at the first vertex only (the table's beyond).
  struct Variant {
    Strategy strategy;
    int cache_entries, product_depth;
    std::string label;
    float max_roughness = kInfinity;
    ProductCompensation compensation = ProductCompensation::Off;
  };
  std::vector<Variant> variants;
  for (Strategy s : strategies) variants.push_back({s, 16, 0, to_string(s)});
  variants.push_back({Strategy::Product, 0, 0, "product, no cache"});
  variants.push_back({Strategy::Product, 16, 1, "product at depth 0 only"});
  // Product at glossy vertices only (the coats, alpha 1e-3) and the table's at the rest.
  variants.push_back({Strategy::Product, 16, 0, "product at alpha <= 0.1 only", 0.1f});
  // The envpis command's default along paths (--product-compensation auto): the compensated product at
  // every vertex, and below a camera ray's hit only (deeper).
  variants.push_back({Strategy::Product, 16, 0, "compensated product", kInfinity, ProductCompensation::On});
  variants.push_back({Strategy::Product, 16, 0, "compensated product below the first hit", 0.5f,
                      ProductCompensation::Deeper});
  for (const Variant& v : variants) {
    RenderOptions o = options(v.strategy, v.strategy == Strategy::Oracle ? 32 : 128, 42);
    o.product_cache.entries = v.cache_entries;
    o.product_depth = v.product_depth;
    o.product_max_roughness = v.max_roughness;
    o.product_compensation = v.compensation;
    const RenderResult r = render(scene, o);
    ASSERT_EQ(r.nonfinite_pixels, 0u) << v.label;
    const auto m = object_means(r, n);
    const auto& ref = v.strategy == Strategy::Mis ? ref_product : ref_mis;
    for (int i : objects) {
      const double se = std::sqrt(m[i].variance + ref[i].variance);
      ASSERT_GT(se, 0.0);
      const double z = (m[i].mean - ref[i].mean) / se;
      EXPECT_LT(std::fabs(z), z_max) << v.label << " object " << scene.objects()[i].name << ": mean " << m[i].mean
                                     << " vs reference " << ref[i].mean;
    }
  }
}

}  // namespace
}  // namespace envpis::render
