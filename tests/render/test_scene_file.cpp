// SPDX-License-Identifier: Apache-2.0
// The renderer's JSON scene files (render/scenes.h, docs/scene-format.md): every object type and
// material loads and renders, the shipped scenes load, the orthographic camera, the environment's
// fields, and one-line errors that name the file and the field for bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "test_util.h"
#include "render/render.h"
#include "render/scenes.h"
#include "test_sky.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;

// A quick render with the renderer's defaults and a small oracle.
RenderResult render_small(const Scene& s, Strategy st, int spp, int width, int height) {
  RenderOptions o;
  o.strategy = st;
  o.spp = spp;
  o.width = width;
  o.height = height;
  o.oracle.resolution = 8;
  return render(s, o);
}

// ---------------------------------------------------------------------------------------------
// Scene files

using test::TempDir;

const char* kObj =
    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
    "f 1 2 3\nf 1 3 4\n";

const char* kPly =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

std::string scene_json(const std::string& objects, const std::string& extra_material = "") {
  return R"({
  // comments are allowed
  "camera": {"from": [0, -8, 2], "to": [0, 0, 0.5], "fov": 40, "width": 48, "height": 32},
  "environment": {"sky": {"width": 64, "height": 32, "sun_radius": 5, "sun_radiance": 20}},
  "materials": {
    "chrome": {"type": "conductor", "roughness": 0.1, "reflectance": [0.9, 0.9, 0.9]},
    "gold": {"type": "conductor", "roughness": 0.25, "eta": [0.143, 0.374, 1.442], "k": [3.983, 2.386, 1.603]},
    "white": {"type": "diffuse", "albedo": 0.8},
    "glass": {"type": "dielectric", "roughness": 0.05, "ior": 1.5},
    "leaf": {"type": "translucent", "transmittance": [0.3, 0.6, 0.2]},
    "plastic": {"type": "coated-diffuse", "albedo": [0.7, 0.1, 0.1], "roughness": 0.1, "ior": 1.5},
    "layered": {"type": "mix", "lobes": [{"type": "diffuse", "weight": 0.6, "albedo": 0.5},
                                         {"type": "conductor", "weight": 0.4, "roughness": 0.2}]})" +
         extra_material + R"(
  },
  "objects": [)" + objects + R"(]
})";
}

TEST(SceneFile, LoadsSpheresObjPlyAndProceduralMeshes) {
  TempDir dir;
  dir.write("quad.obj", kObj);
  dir.write("tri.ply", kPly);
  const std::string path = dir.write(
      "scene.json", scene_json(R"(
    {"type": "sphere", "name": "ball", "center": [0, 0, 1], "radius": 1, "material": "gold"},
    {"type": "sphere", "center": [2, 0, 1], "radius": 0.5, "material": "glass"},
    {"type": "sphere", "center": [-2, 0, 1], "radius": 0.5, "material": "layered"},
    {"type": "sphere", "center": [-2, 2, 1], "radius": 0.5, "material": "leaf"},
    {"type": "sphere", "center": [2, 2, 1], "radius": 0.5, "material": "plastic"},
    {"type": "mesh", "name": "floor", "file": "quad.obj", "material": "white", "scale": 5},
    {"type": "mesh", "file": "tri.ply", "material": "chrome", "translate": [0, 3, 0], "rotate": [90, 0, 0]},
    {"type": "torus-knot", "material": "chrome", "scale": 0.3, "translate": [0, 0, 3], "segments": 60, "sides": 8}
  )"));
  const Scene s = load_scene_file(path);
  ASSERT_EQ(s.objects().size(), 8u);
  EXPECT_EQ(s.objects()[0].name, "ball");
  EXPECT_EQ(s.objects()[5].name, "floor");
  EXPECT_EQ(s.objects()[5].triangles, 2u);
  EXPECT_EQ(s.objects()[6].triangles, 1u);
  EXPECT_EQ(s.camera().width, 48);
  EXPECT_TRUE(s.material(s.find_material("glass")).transmissive);
  EXPECT_TRUE(s.material(s.find_material("leaf")).transmissive);
  EXPECT_FALSE(s.material(s.find_material("gold")).transmissive);
  // The floor's normal faces up: a ray from above hits it from its front.
  SurfaceHit hit;
  ASSERT_TRUE(s.intersect({{3.5f, -3.5f, 5}, {0, 0, -1}, kInfinity}, &hit));
  EXPECT_EQ(hit.object, 5);
  EXPECT_NEAR(hit.ng.z, 1.0f, 1e-5f);
  EXPECT_NEAR(hit.t, 5.0f, 1e-4f);
  for (Strategy st : all_strategies()) {
    RenderOptions o;
    o.strategy = st;
    o.spp = 2;
    o.oracle.resolution = 8;
    const RenderResult r = render(s, o);
    EXPECT_EQ(r.width, 48);
    EXPECT_EQ(r.nonfinite_pixels, 0u) << to_string(st);
  }
}

// The JSON scenes in scenes/ (used by the measurements in BENCHMARKS.md) load, and every strategy
// renders them, with the path integrator, to a finite image.
TEST(SceneFile, ShippedScenesLoadAndRender) {
  const fs::path dir = fs::path(ENVPIS_SOURCE_DIR) / "scenes";
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    const Scene s = load_scene_file(entry.path().string(), test_sky());
    EXPECT_GE(s.objects().size(), 3u) << entry.path();
    for (Strategy st : all_strategies()) {
      const RenderResult r = render_small(s, st, 1, 32, 8);
      EXPECT_EQ(r.nonfinite_pixels, 0u) << entry.path() << " " << to_string(st);
    }
  }
  EXPECT_GE(count, 2);
}

// scene_json(objects) with the camera's "fov": 40 replaced by `fields`.
std::string with_camera(const std::string& objects, const std::string& fields) {
  std::string text = scene_json(objects);
  const std::string fov = R"("fov": 40)";
  return text.replace(text.find(fov), fov.size(), fields);
}

// An orthographic camera's primary rays all run along the view direction, from a film of the stated
// height (and width = height * aspect) centred on 'from'; the perspective camera's all leave 'from'.
TEST(Camera, OrthographicRaysAreParallelAndSpanTheFilm) {
  CameraSpec spec;
  spec.from = {1, -5, 2};
  spec.to = {1, 0, 2};
  spec.projection = Projection::Orthographic;
  spec.ortho_height = 3;
  const int W = 60, H = 20;
  const Camera cam(spec, W, H);
  for (float fy : {0.0f, 7.5f, 20.0f})
    for (float fx : {0.0f, 13.25f, 60.0f}) {
      const Ray r = cam.generate_ray(fx, fy);
      EXPECT_NEAR(length(r.direction - Vec3{0, 1, 0}), 0.0f, 1e-6f);
      EXPECT_NEAR(r.origin.y, -5.0f, 1e-5f);  // on the film plane through 'from'
    }
  // The corners: right is +X, up is +Z; the film is 9 x 3 (aspect 3) around 'from'.
  const Ray tl = cam.generate_ray(0, 0), br = cam.generate_ray(W, H), c = cam.generate_ray(0.5f * W, 0.5f * H);
  EXPECT_NEAR(length(tl.origin - Vec3{1 - 4.5f, -5, 2 + 1.5f}), 0.0f, 1e-5f);
  EXPECT_NEAR(length(br.origin - Vec3{1 + 4.5f, -5, 2 - 1.5f}), 0.0f, 1e-5f);
  EXPECT_NEAR(length(c.origin - spec.from), 0.0f, 1e-5f);
  // The perspective camera is unchanged: every ray from 'from', the centre one along the view.
  spec.projection = Projection::Perspective;
  const Camera persp(spec, W, H);
  EXPECT_NEAR(length(persp.generate_ray(3, 17).origin - spec.from), 0.0f, 0.0f);
  EXPECT_NEAR(length(persp.generate_ray(0.5f * W, 0.5f * H).direction - Vec3{0, 1, 0}), 0.0f, 1e-6f);
  EXPECT_GT(dot(persp.generate_ray(0, 0).direction, Vec3{-1, 0, 0}), 0.1f);
  // A film height must be positive and finite.
  spec.projection = Projection::Orthographic;
  for (float bad : {0.0f, -1.0f, std::nanf(""), INFINITY}) {
    spec.ortho_height = bad;
    EXPECT_THROW(Camera(spec, W, H), Error) << bad;
  }
}

// A scene file with an orthographic camera renders finite images with every strategy, and the unit
// sphere covers the part of the 4-unit-high film that a disc of radius 1 does.
TEST(SceneFile, OrthographicCameraRenders) {
  TempDir dir;
  std::string text = with_camera(R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "gold"})",
                                 R"("type": "orthographic", "ortho_height": 4)");
  text.replace(text.find(R"("to": [0, 0, 0.5])"), 17, R"("to": [0, 0, 1])");
  text.replace(text.find(R"("from": [0, -8, 2])"), 18, R"("from": [0, -8, 1])");
  const Scene s = load_scene_file(dir.write("ortho.json", text));
  EXPECT_EQ(s.camera().projection, Projection::Orthographic);
  EXPECT_EQ(s.camera().ortho_height, 4.0f);
  for (Strategy st : all_strategies()) {
    const RenderResult r = render_small(s, st, 2, 96, 64);
    EXPECT_EQ(r.nonfinite_pixels, 0u) << to_string(st);
    EXPECT_EQ(r.nonfinite_pixels, 0u) << to_string(st);
    if (st != Strategy::Bsdf) continue;
    const double sphere = std::count(r.object_id.begin(), r.object_id.end(), 0);
    const double film = 4.0 * 6.0;  // world units: 4 high, 6 wide
    EXPECT_NEAR(sphere / r.object_id.size() * film, M_PI, 0.1);
  }
}

// An environment file's "orientation" and "filter" fields reach the map (default: panorama, bilinear).
TEST(SceneFile, EnvironmentOrientationAndFilterFields) {
  const std::string sunset = std::string(kBlenderWorldDir) + "/sunset.exr";
  if (!fs::exists(sunset)) GTEST_SKIP() << "no " << sunset;
  TempDir dir;
  std::string text = scene_json(R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "gold"})");
  const std::size_t sky = text.find(R"({"sky")"), sky_end = text.find('}', text.find('}', sky) + 1);
  std::string legacy = text;
  legacy.replace(sky, sky_end + 1 - sky, R"({"file": ")" + sunset + R"(", "orientation": "legacy", "filter": "nearest"})");
  const Scene a = load_scene_file(dir.write("legacy.json", legacy));
  EXPECT_EQ(a.environment().orientation(), LatLongOrientation::Legacy);
  EXPECT_EQ(a.environment().filter(), MapFilter::Nearest);
  text.replace(sky, sky_end + 1 - sky, R"({"file": ")" + sunset + R"("})");
  const Scene b = load_scene_file(dir.write("default.json", text));
  EXPECT_EQ(b.environment().orientation(), LatLongOrientation::Panorama);
  EXPECT_EQ(b.environment().filter(), MapFilter::Bilinear);
}

std::string load_error(const std::string& text, const TempDir& dir) {
  const std::string path = dir.write("bad.json", text);
  try {
    load_scene_file(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// "closed_surfaces": false in a scene file turns the closed-surface proxy off; the default is on, and
// Scene::set_proxy_closed_surfaces switches it after commit() too (what --closed-surfaces does).
TEST(SceneFile, ClosedSurfacesSwitch) {
  TempDir dir;
  const std::string sphere = R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "glass"})";
  std::string off = scene_json(sphere);
  off.insert(off.find('{') + 1, R"("closed_surfaces": false,)");
  Scene on_scene = load_scene_file(dir.write("on.json", scene_json(sphere)));
  Scene off_scene = load_scene_file(dir.write("off.json", off));
  const int glass = on_scene.find_material("glass");
  ASSERT_GE(glass, 0);
  EXPECT_TRUE(on_scene.proxy_closed_surfaces());
  EXPECT_TRUE(on_scene.material(glass).bsdf.closed_surface());
  EXPECT_FALSE(off_scene.proxy_closed_surfaces());
  EXPECT_FALSE(off_scene.material(off_scene.find_material("glass")).bsdf.closed_surface());
  on_scene.set_proxy_closed_surfaces(false);
  EXPECT_FALSE(on_scene.material(glass).bsdf.closed_surface());
  on_scene.set_proxy_closed_surfaces(true);
  EXPECT_TRUE(on_scene.material(glass).bsdf.closed_surface());
  std::string bad = scene_json(sphere);
  bad.insert(bad.find('{') + 1, R"("closed_surfaces": "yes",)");
  EXPECT_THROW(load_scene_file(dir.write("bad.json", bad)), Error);
}

TEST(SceneFile, CleanErrorsForBadFilesAndFields) {
  TempDir dir;
  dir.write("quad.obj", kObj);
  dir.write("garbage.obj", "this is not an obj file\n\x01\x02\x03");
  const std::string sphere = R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "gold"})";
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases{
      {"{ not json", "invalid JSON"},
      {scene_json(R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "nope"})"),
       "objects[0].material: unknown material 'nope'"},
      {scene_json(R"({"type": "sphere", "center": [0, 0], "radius": 1, "material": "gold"})"),
       "objects[0].center: expected an array of 3 numbers"},
      {scene_json(R"({"type": "sphere", "center": [0, 0, 1], "radius": -1, "material": "gold"})"),
       "objects[0].radius: must be positive"},
      {scene_json(R"({"type": "sphere", "centre": [0, 0, 1], "radius": 1, "material": "gold"})"),
       "objects[0]: missing field 'center'"},
      {scene_json(R"({"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "gold", "colour": 1})"),
       "objects[0]: unknown field 'colour'"},
      {scene_json(R"({"type": "cube", "material": "gold"})"), "objects[0].type: unknown object type 'cube'"},
      {scene_json(R"({"type": "mesh", "file": "missing.obj", "material": "gold"})"), "does not exist"},
      {scene_json(R"({"type": "mesh", "file": "garbage.obj", "material": "gold"})"), "objects[0].file"},
      {scene_json(sphere, R"(, "bad": {"type": "velvet"})"), "materials.bad.type: unknown material type 'velvet'"},
      {scene_json(sphere, R"(, "bad": {"type": "conductor", "roughness": 2})"), "materials.bad.roughness: must be in"},
      {scene_json(sphere, R"(, "bad": {"type": "diffuse", "albedo": [1, 2]})"), "materials.bad.albedo"},
      {scene_json("").replace(scene_json("").find("\"sky\""), 5, "\"file\": \"nope.exr\", \"x\""),
       "environment"},
      {scene_json(sphere).replace(scene_json(sphere).find("\"fov\": 40"), 9, "\"fov\": 400"), "camera.fov"},
      {with_camera(sphere, R"("type": "fisheye")"), "camera.type: unknown camera type 'fisheye'"},
      {with_camera(sphere, R"("type": "orthographic")"), "camera: missing field 'ortho_height'"},
      {with_camera(sphere, R"("type": "orthographic", "ortho_height": 0)"), "camera.ortho_height: must be a positive"},
      {with_camera(sphere, R"("type": "orthographic", "ortho_height": -2)"), "camera.ortho_height: must be a positive"},
      {with_camera(sphere, R"("type": "orthographic", "ortho_height": 1e300)"), "camera.ortho_height: must be a positive"},
      {with_camera(sphere, R"("type": "orthographic", "ortho_height": "big")"), "camera.ortho_height: expected a number"},
      {with_camera(sphere, R"("type": "orthographic", "ortho_height": 2, "fov": 30)"), "camera.fov: an orthographic"},
      {with_camera(sphere, R"("ortho_height": 2)"), "camera.ortho_height: only an orthographic camera"},
      {scene_json("").replace(scene_json("").find("\"sky\""), 5, "\"file\": \"x.exr\", \"orientation\": \"up\", \"x\""),
       "environment.orientation: unknown lat-long orientation 'up'"},
      {scene_json("").replace(scene_json("").find("\"sky\""), 5, "\"file\": \"x.exr\", \"filter\": \"cubic\", \"x\""),
       "environment.filter: unknown map filter 'cubic'"},
  };
  for (const Case& c : cases) {
    const std::string err = load_error(c.text, dir);
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in '" << err << "'";
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
  try {
    load_scene("no-such-scene");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown scene"), std::string::npos);
  }
}

}  // namespace
}  // namespace envpis::render
