// SPDX-License-Identifier: Apache-2.0
// JSON scene files (docs/scene-format.md) and load_scene of render/scenes.h.
#include "render/scenes.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "render/gltf.h"
#include "render/scene_fields.h"
#include "render/scene_portals.h"

namespace envpis::render {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Scene files

namespace {

using detail::Fields;

/// A file name from a scene file: ${NAME} expands to an asset directory (docs/assets.md) and a
/// relative name is relative to the scene file's directory.
std::string scene_path(const Fields& f, const std::string& key, const fs::path& dir) {
  std::string file = f.string(key), out;
  for (std::size_t i = 0; i < file.size();) {
    if (file.compare(i, 2, "${") != 0) {
      out += file[i++];
      continue;
    }
    const std::size_t end = file.find('}', i);
    if (end == std::string::npos) f.fail_at(f.sub(key), "unterminated ${ in '" + file + "'");
    const std::string name = file.substr(i + 2, end - i - 2);
    try {
      out += asset_directory(name);
    } catch (const Error& e) {
      f.fail_at(f.sub(key), e.what());
    }
    i = end + 1;
  }
  if (fs::path(out).is_relative()) out = (dir / out).string();
  return out;
}

struct LobeSpec {
  std::shared_ptr<const Lobe> lobe;
  bool transmissive = false;
};

LobeSpec parse_lobe(const Fields& f) {
  const std::string type = f.string("type");
  LobeSpec out;
  if (type == "diffuse" || type == "lambert") {
    out.lobe = make_lambert(f.color("albedo", {0.8f, 0.8f, 0.8f}));
  } else if (type == "translucent") {
    out.lobe = make_translucent(f.color("transmittance", {0.5f, 0.5f, 0.5f}));
    out.transmissive = true;
  } else if (type == "conductor") {
    const float alpha = f.number_in("roughness", 0.2f, 0.0f, 1.0f);
    const bool has_f0 = f.has("reflectance"), has_ior = f.has("eta") || f.has("k");
    if (has_f0 && has_ior) f.fail("give either 'reflectance' or 'eta' and 'k', not both");
    if (has_ior) {
      const Rgb eta = f.color("eta", {1, 1, 1}, 0.0f, 100.0f), k = f.color("k", {0, 0, 0}, 0.0f, 100.0f);
      out.lobe = make_conductor(alpha, eta, k);
    } else {
      out.lobe = make_conductor_reflectance(alpha, f.color("reflectance", {0.9f, 0.9f, 0.9f}));
    }
  } else if (type == "dielectric" || type == "glass") {
    const float alpha = f.number_in("roughness", 0.0f, 0.0f, 1.0f);
    const float ior = f.number_in("ior", 1.5f, 1.0f, 4.0f);
    out.lobe = make_dielectric(alpha, ior, f.color("tint", {1, 1, 1}));
    out.transmissive = true;
  } else if (type == "coated-diffuse" || type == "plastic") {
    const Rgb base = f.color("albedo", {0.5f, 0.5f, 0.5f});
    const float alpha = f.number_in("roughness", 0.1f, 0.0f, 1.0f);
    const float ior = f.number_in("ior", 1.5f, 1.0f, 4.0f);
    out.lobe = make_coated_diffuse(base, alpha, ior);
  } else {
    f.fail_at(f.sub("type"), "unknown material type '" + type +
                                 "' (expected diffuse, translucent, conductor, dielectric, coated-diffuse, pbr or mix)");
  }
  return out;
}

/// A texture of a "pbr" material: a file name or {"file", "offset", "rotation", "scale", "wrap"}.
TextureRef parse_texture(const Fields& owner, const std::string& key, const fs::path& dir, bool srgb, bool roughness_only) {
  TextureRef r;
  if (!owner.has(key)) return r;
  std::string file;
  if (owner.get(key).is_string()) {
    file = scene_path(owner, key, dir);
  } else {
    Fields t = owner.object(key);
    file = scene_path(t, "file", dir);
    if (t.has("offset")) {
      const Vec3 o = t.vec3("offset");
      r.transform.offset = {o.x, o.y};
    }
    if (t.has("scale")) {
      const Vec3 sc = t.vec3("scale");
      r.transform.scale = {sc.x, sc.y};
    }
    r.transform.rotation = t.number("rotation", 0.0f) * kPi / 180.0f;
    const std::string wrap = t.string("wrap", "repeat");
    if (wrap == "clamp") r.wrap_s = r.wrap_t = TextureWrap::Clamp;
    else if (wrap == "mirror") r.wrap_s = r.wrap_t = TextureWrap::Mirror;
    else if (wrap != "repeat") t.fail_at(t.sub("wrap"), "expected repeat, clamp or mirror");
    t.finish();
  }
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) owner.fail_at(owner.sub(key), "texture file '" + file + "' does not exist");
  try {
    r.texture = Texture::load_file(file, srgb, "texture");
  } catch (const Error& e) {
    owner.fail_at(owner.sub(key), e.what());
  }
  if (roughness_only) {  // roughness from G (a grey image, or glTF's metallic-roughness layout), metallic 1
    const Texture& t = *r.texture;
    std::vector<float> px;
    px.reserve(std::size_t(t.width()) * t.height() * 4);
    for (int y = 0; y < t.height(); ++y)
      for (int x = 0; x < t.width(); ++x) px.insert(px.end(), {0.0f, t.texel(x, y).g, 1.0f, 1.0f});
    r.texture = std::make_shared<const Texture>(t.width(), t.height(), std::move(px));
  }
  return r;
}

SceneMaterial parse_pbr_material(const Fields& f, const std::string& name, const fs::path& dir) {
  PbrParams p;
  p.base_color = f.color("base_color", {0.8f, 0.8f, 0.8f});
  p.metallic = f.number_in("metallic", 0.0f, 0.0f, 1.0f);
  p.roughness = f.number_in("roughness", 0.5f, 0.0f, 1.0f);
  p.transmission = f.number_in("transmission", 0.0f, 0.0f, 1.0f);
  p.ior = f.number_in("ior", 1.5f, 1.0f, 4.0f);
  p.clearcoat = f.number_in("clearcoat", 0.0f, 0.0f, 1.0f);
  p.clearcoat_roughness = f.number_in("clearcoat_roughness", 0.0f, 0.0f, 1.0f);
  p.emissive = f.color("emissive", {0, 0, 0}, 0.0f, 1e6f);
  PbrTextures t;
  t.base_color = parse_texture(f, "base_color_texture", dir, true, false);
  if (f.has("metallic_roughness_texture") && f.has("roughness_texture"))
    f.fail("give either 'metallic_roughness_texture' or 'roughness_texture', not both");
  t.metallic_roughness = parse_texture(f, "metallic_roughness_texture", dir, false, false);
  if (!t.metallic_roughness) t.metallic_roughness = parse_texture(f, "roughness_texture", dir, false, true);
  t.normal = parse_texture(f, "normal_texture", dir, false, false);
  t.normal_scale = f.number_in("normal_scale", 1.0f, -100.0f, 100.0f);
  t.emissive = parse_texture(f, "emissive_texture", dir, true, false);
  f.finish();
  try {
    return make_pbr_scene_material(name, std::make_shared<const PbrMaterial>(p, std::move(t)));
  } catch (const Error& e) {
    f.fail(e.what());
  }
}

SceneMaterial parse_material(const Fields& f, const std::string& name, const fs::path& dir) {
  SceneMaterial m;
  m.name = name;
  const std::string type = f.string("type");
  if (type == "pbr") return parse_pbr_material(f, name, dir);
  if (type == "mix") {
    const json& lobes = f.get("lobes");
    if (!lobes.is_array() || lobes.empty()) f.fail_at(f.sub("lobes"), "expected a non-empty array of lobes");
    for (std::size_t i = 0; i < lobes.size(); ++i) {
      Fields lf(lobes[i], f.sub("lobes") + "[" + std::to_string(i) + "]", &f.file());
      const float w = lf.number_in("weight", 1.0f, 0.0f, 1e6f);
      if (lf.string("type") == "mix") lf.fail("a mix cannot contain a mix");
      LobeSpec ls = parse_lobe(lf);
      lf.finish();
      m.bsdf.add(ls.lobe, w);
      m.transmissive = m.transmissive || ls.transmissive;
    }
  } else {
    LobeSpec ls = parse_lobe(f);
    m.bsdf.add(ls.lobe, 1.0f);
    m.transmissive = ls.transmissive;
  }
  f.finish();
  return m;
}

/// Rotation matrix for Euler angles in degrees, applied about X, then Y, then Z.
Mat3 euler_xyz(Vec3 deg) {
  auto rot = [](int axis, float degrees) {
    const float a = degrees * kPi / 180.0f, c = std::cos(a), s = std::sin(a);
    Mat3 r;
    const int i = (axis + 1) % 3, j = (axis + 2) % 3;
    r.m[i][i] = c;
    r.m[i][j] = -s;
    r.m[j][i] = s;
    r.m[j][j] = c;
    return r;
  };
  auto mul = [](const Mat3& a, const Mat3& b) {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return r;
  };
  return mul(rot(2, deg.z), mul(rot(1, deg.y), rot(0, deg.x)));
}

TriangleMesh load_mesh_file(const std::string& file, bool smooth, const Fields& f) {
  std::error_code ec;
  if (!fs::exists(file, ec)) f.fail_at(f.sub("file"), "mesh file '" + file + "' does not exist");
  Assimp::Importer importer;
  unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                   aiProcess_SortByPType;
  flags |= smooth ? aiProcess_GenSmoothNormals : aiProcess_DropNormals;
  const aiScene* sc = importer.ReadFile(file, flags);
  if (!sc || (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !sc->mRootNode)
    f.fail_at(f.sub("file"), "cannot read mesh '" + file + "': " + importer.GetErrorString());
  TriangleMesh m;
  bool all_normals = true;
  for (unsigned i = 0; i < sc->mNumMeshes; ++i) all_normals = all_normals && sc->mMeshes[i]->HasNormals();
  for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
    const aiMesh* am = sc->mMeshes[i];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const std::uint32_t base = static_cast<std::uint32_t>(m.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      m.positions.push_back({am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z});
      if (smooth && all_normals) m.normals.push_back({am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z});
    }
    for (unsigned t = 0; t < am->mNumFaces; ++t) {
      const aiFace& face = am->mFaces[t];
      if (face.mNumIndices != 3) continue;
      m.indices.insert(m.indices.end(), {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (m.indices.empty()) f.fail_at(f.sub("file"), "mesh '" + file + "' has no triangle");
  return m;
}

/// An object's transform: scale, then rotation, then translation.
struct Transform {
  Vec3 scale{1, 1, 1};
  Mat3 rotation;
  Vec3 translation{0, 0, 0};
  Vec3 point(Vec3 p) const { return rotation * mul(p, scale) + translation; }
  void apply(TriangleMesh& m) const {
    for (Vec3& p : m.positions) p = point(p);
    const Vec3 inv{1 / scale.x, 1 / scale.y, 1 / scale.z};
    for (Vec3& n : m.normals) n = rotation * mul(n, inv);
    if (scale.x * scale.y * scale.z < 0)  // a mirroring transform flips the winding
      for (std::size_t k = 0; k < m.indices.size(); k += 3) std::swap(m.indices[k + 1], m.indices[k + 2]);
  }
};

Transform parse_transform(const Fields& f) {
  Transform tr;
  if (f.has("scale")) {
    const json& s = f.get("scale");
    if (s.is_number()) {
      const float k = f.number("scale");
      tr.scale = {k, k, k};
    } else {
      tr.scale = f.vec3("scale");
    }
    if (!(tr.scale.x != 0 && tr.scale.y != 0 && tr.scale.z != 0)) f.fail_at(f.sub("scale"), "must be non-zero");
  }
  tr.rotation = euler_xyz(f.vec3("rotate", {0, 0, 0}));
  tr.translation = f.vec3("translate", {0, 0, 0});
  return tr;
}

std::shared_ptr<const EnvironmentMap> parse_environment(const Fields& f, const fs::path& dir, std::string* desc) {
  if (f.has("sky")) {
    if (f.has("file")) f.fail("give either 'file' or 'sky', not both");
    Fields s = f.object("sky");
    SkyOptions o;
    o.width = s.integer("width", o.width, 4, 16384);
    o.height = s.integer("height", o.height, 2, 8192);
    o.sun_elevation = s.number_in("sun_elevation", o.sun_elevation, -90, 90);
    o.sun_azimuth = s.number("sun_azimuth", o.sun_azimuth);
    o.sun_radius = s.number_in("sun_radius", o.sun_radius, 0.01f, 89.0f);
    o.sun_radiance = s.number_in("sun_radiance", o.sun_radiance, 0, 1e9f);
    o.sky_radiance = s.number_in("sky_radiance", o.sky_radiance, 0, 1e9f);
    o.ground_radiance = s.number_in("ground_radiance", o.ground_radiance, 0, 1e9f);
    s.finish();
    f.finish();
    *desc = "procedural sky";
    return std::make_shared<const EnvironmentMap>(make_procedural_sky(o));
  }
  const std::string file = scene_path(f, "file", dir);
  EnvironmentMapOptions mo;
  mo.rotation = Mat3::rotate_z(f.number("rotation", 0.0f));
  mo.scale = f.number_in("scale", 1.0f, 0.0f, 1e9f);
  // An optional named value read with the library's parser, whose error names the field.
  auto named = [&f](const std::string& key, auto parse, auto value) {
    if (!f.has(key)) return value;
    try {
      return parse(f.string(key));
    } catch (const Error& e) {
      f.fail_at(f.sub(key), e.what());
    }
  };
  mo.layout = named("layout", parse_map_layout, mo.layout);
  mo.orientation = named("orientation", parse_latlong_orientation, mo.orientation);
  mo.filter = named("filter", parse_map_filter, mo.filter);
  f.finish();
  *desc = file;
  try {
    return std::make_shared<const EnvironmentMap>(EnvironmentMap::load(file, mo));
  } catch (const Error& e) {
    f.fail_at(f.sub("file"), e.what());
  }
}

void check_camera(const CameraSpec& cam, const Fields& f);

CameraSpec parse_camera(const Fields& cf) {
  CameraSpec cam;
  cam.from = cf.vec3("from");
  cam.to = cf.vec3("to");
  cam.up = cf.vec3("up", {0, 0, 1});
  const std::string type = cf.string("type", "perspective");
  if (type == "perspective") {
    if (cf.has("ortho_height")) cf.fail_at(cf.sub("ortho_height"), "only an orthographic camera has a film height");
    cam.vfov_degrees = cf.number_in("fov", 40.0f, 0.01f, 179.0f);
  } else if (type == "orthographic") {
    if (cf.has("fov")) cf.fail_at(cf.sub("fov"), "an orthographic camera has no field of view (give ortho_height)");
    cam.projection = Projection::Orthographic;
    cam.ortho_height = cf.number("ortho_height");
    if (!(cam.ortho_height > 0 && std::isfinite(cam.ortho_height)))
      cf.fail_at(cf.sub("ortho_height"), "must be a positive finite number");
  } else {
    cf.fail_at(cf.sub("type"), "unknown camera type '" + type + "' (expected perspective or orthographic)");
  }
  cam.width = cf.integer("width", 640, 1, 16384);
  cam.height = cf.integer("height", 360, 1, 16384);
  cf.finish();
  check_camera(cam, cf);
  return cam;
}

void check_camera(const CameraSpec& cam, const Fields& f) {
  try {
    Camera check(cam, cam.width, cam.height);
  } catch (const Error& e) {
    f.fail(e.what());
  }
}

/// A glTF object: one mesh per glTF material (or all with the scene material `material`), named
/// "<name>/<glTF material>"; with "use_camera": true the file's camera, transformed, is the scene's.
/// The file's portal nodes, transformed, are added to `portals`.
void add_gltf_object(Scene& s, const Fields& f, const fs::path& dir, const std::string& name,
                     std::optional<CameraSpec>& camera, Portals& portals) {
  const std::string file = scene_path(f, "file", dir);
  GltfModel model;
  try {
    model = load_gltf(file);
  } catch (const Error& e) {
    f.fail_at(f.sub("file"), e.what());
  }
  const Transform tr = parse_transform(f);
  int override_material = -1;
  if (f.has("material")) {
    const std::string mname = f.string("material");
    override_material = s.find_material(mname);
    if (override_material < 0) f.fail_at(f.sub("material"), "unknown material '" + mname + "'");
  }
  if (f.boolean("use_camera", false)) {
    if (camera) f.fail_at(f.sub("use_camera"), "the scene already has a camera");
    if (!model.camera) f.fail_at(f.sub("use_camera"), "'" + file + "' has no camera");
    CameraSpec c = *model.camera;
    c.from = tr.point(c.from);
    c.to = tr.point(c.to);
    c.up = tr.rotation * c.up;
    if (c.projection == Projection::Orthographic) c.ortho_height *= std::fabs(tr.scale.z);
    c.width = f.integer("width", c.width, 1, 16384);
    c.height = f.integer("height", c.height, 1, 16384);
    check_camera(c, f);
    camera = c;
  }
  f.finish();
  for (const GltfModel::Portal& p : model.portals) {
    Quad q;
    for (int i = 0; i < 4; ++i) q.v[i] = tr.point(p.quad.v[i]);
    if (tr.scale.x * tr.scale.y * tr.scale.z < 0) std::swap(q.v[1], q.v[3]);  // keep it counter-clockwise from outside
    add_portal(portals, q, f.file() + ": " + f.sub("file") + ": " + file + ": portal node '" + p.node + "'");
  }
  if (override_material >= 0) {
    TriangleMesh all;
    bool uvs = true;  // kept when every part has them (a textured replacement material needs them)
    for (const GltfModel::Part& p : model.parts) uvs = uvs && !p.mesh.uvs.empty();
    for (GltfModel::Part& p : model.parts) {
      const std::uint32_t base = std::uint32_t(all.positions.size());
      all.positions.insert(all.positions.end(), p.mesh.positions.begin(), p.mesh.positions.end());
      all.normals.insert(all.normals.end(), p.mesh.normals.begin(), p.mesh.normals.end());
      if (uvs) all.uvs.insert(all.uvs.end(), p.mesh.uvs.begin(), p.mesh.uvs.end());
      for (std::uint32_t i : p.mesh.indices) all.indices.push_back(base + i);
    }
    tr.apply(all);
    s.add_mesh(name, std::move(all), override_material);
    return;
  }
  std::vector<int> ids(model.materials.size(), -1);
  for (GltfModel::Part& p : model.parts) {
    int& id = ids[std::size_t(p.material)];
    if (id < 0) {
      SceneMaterial m = model.materials[std::size_t(p.material)];
      m.name = name + "/" + m.name;
      id = s.add_material(std::move(m));
    }
    tr.apply(p.mesh);
    s.add_mesh(name + "/" + p.name, std::move(p.mesh), id);
  }
}

}  // namespace

Scene load_scene_file(const std::string& path, std::shared_ptr<const EnvironmentMap> env) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".gltf" || ext == ".glb") return load_gltf_scene(path, env);
  std::ifstream in(path);
  if (!in) throw Error("cannot open scene file '" + path + "'");
  json j;
  try {
    j = json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const json::exception& e) {  // also out_of_range: a number too large for a double (1e999)
    throw Error(path + ": invalid JSON: " + e.what());
  }
  const fs::path dir = fs::path(path).parent_path();
  Fields top(j, "", &path);
  Scene s;

  // camera (may come from a glTF object's file instead, see below)
  std::optional<CameraSpec> camera;
  if (top.has("camera")) camera = parse_camera(top.object("camera"));

  // environment (optional when overridden)
  std::string desc;
  if (top.has("environment") && !env)  // an override (--env) replaces the file's environment
    env = parse_environment(top.object("environment"), dir, &desc);
  if (!env) env = default_environment(&desc);
  else if (desc.empty()) desc = env->path().empty() ? "user map" : env->path();
  s.set_environment(env);
  s.set_environment_description(desc);

  // materials (a scene of glTF objects may have none of its own)
  static const json kNoMaterials = json::object();
  const json* mats_ptr = &kNoMaterials;
  if (top.has("materials")) {
    (void)top.object("materials");  // must be an object
    mats_ptr = &top.get("materials");
  }
  const json& mats = *mats_ptr;
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    Fields f(it.value(), "materials." + it.key(), &path);
    s.add_material(parse_material(f, it.key(), dir));
  }

  // objects (a glTF object's portal nodes join the scene's portals, before the file's own "portals")
  Portals portals;
  const json& objs = top.get("objects");
  if (!objs.is_array() || objs.empty()) top.fail_at("objects", "expected a non-empty array");
  for (std::size_t i = 0; i < objs.size(); ++i) {
    Fields f(objs[i], "objects[" + std::to_string(i) + "]", &path);
    const std::string type = f.string("type");
    std::string name = f.string("name", type + "-" + std::to_string(i));
    if (type == "gltf") {
      add_gltf_object(s, f, dir, name, camera, portals);
      continue;
    }
    const std::string mname = f.string("material");
    const int mat = s.find_material(mname);
    if (mat < 0) f.fail_at(f.sub("material"), "unknown material '" + mname + "'");
    if (type == "sphere") {
      const Vec3 c = f.vec3("center");
      const float r = f.number("radius");
      if (!(r > 0)) f.fail_at(f.sub("radius"), "must be positive");
      f.finish();
      s.add_sphere(name, c, r, mat);
    } else if (type == "mesh" || type == "torus-knot" || type == "quad") {
      TriangleMesh m;
      if (type == "mesh") {
        const std::string file = scene_path(f, "file", dir);
        m = load_mesh_file(file, f.boolean("smooth", true), f);
      } else if (type == "torus-knot") {
        m = make_torus_knot(f.integer("p", 2, 1, 32), f.integer("q", 3, 1, 32), f.number_in("major", 2.0f, 0, 1e6f),
                            f.number_in("minor", 0.9f, 0, 1e6f), f.number_in("tube", 0.42f, 1e-6f, 1e6f),
                            f.integer("segments", 600, 3, 100000), f.integer("sides", 32, 3, 4096));
      } else {
        const float size = f.number_in("size", 10.0f, 1e-6f, 1e9f);
        m = make_quad({0, 0, 0}, 0.5f * size, 0.5f * size);
      }
      parse_transform(f).apply(m);
      f.finish();
      s.add_mesh(name, std::move(m), mat);
    } else {
      f.fail_at(f.sub("type"), "unknown object type '" + type + "' (expected sphere, mesh, torus-knot, quad or gltf)");
    }
  }
  if (!camera) top.fail("missing field 'camera' (or a gltf object with \"use_camera\": true)");
  s.set_camera(*camera);
  // Closed-surface proxy (docs/proxy.md): on unless the file says otherwise.
  s.set_proxy_closed_surfaces(top.boolean("closed_surfaces", true));
  s.set_widen_bent_normals(top.boolean("widen_bent_normals", true));
  if (top.has("portals")) portals = parse_portals(top.get("portals"), path, std::move(portals));
  s.set_portals(std::move(portals));
  top.finish();
  s.commit();
  return s;
}

std::string asset_directory(const std::string& name) {
  auto env_or = [](const char* var, std::string def) {
    const char* v = std::getenv(var);
    return v && *v ? std::string(v) : def;
  };
  if (name == "ASSIMP_MODELS") return env_or("ENVPIS_ASSIMP_MODELS", "/usr/share/assimp/models");
  if (name == "BLENDER_WORLDS") return kBlenderWorldDir;
  if (name == "ENVPIS_ASSETS") {
    const char* home = std::getenv("HOME");
    const std::string cache = env_or("XDG_CACHE_HOME", std::string(home ? home : ".") + "/.cache");
    return env_or("ENVPIS_ASSETS", cache + "/envpis/assets");
  }
  throw Error("unknown variable ${" + name + "} (expected ASSIMP_MODELS, ENVPIS_ASSETS or BLENDER_WORLDS)");
}

Scene load_gltf_scene(const std::string& path, std::shared_ptr<const EnvironmentMap> env) {
  GltfModel model = load_gltf(path);
  Scene s;
  Vec3 lo{kInfinity, kInfinity, kInfinity}, hi = -lo;
  for (const GltfModel::Part& p : model.parts)
    for (const Vec3& v : p.mesh.positions) {
      lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
      hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
    }
  std::vector<int> ids(model.materials.size(), -1);
  for (GltfModel::Part& p : model.parts) {
    int& id = ids[std::size_t(p.material)];
    if (id < 0) id = s.add_material(model.materials[std::size_t(p.material)]);
    s.add_mesh(p.name, std::move(p.mesh), id);
  }
  CameraSpec cam;
  if (model.camera) {
    cam = *model.camera;
  } else {  // frame the bounding sphere from the front (-Y), 20 degrees above, with a 40 degree fov
    const Vec3 c = (lo + hi) * 0.5f;
    const float r = std::max(0.5f * length(hi - lo), 1e-3f);
    const float dist = r / std::sin(0.5f * 40.0f * kPi / 180.0f);
    const float el = 20.0f * kPi / 180.0f;
    cam.from = c + Vec3{0, -std::cos(el), std::sin(el)} * dist;
    cam.to = c;
    cam.vfov_degrees = 40.0f;
  }
  s.set_camera(cam);
  Portals portals;  // already validated by load_gltf
  for (const GltfModel::Portal& p : model.portals) add_portal(portals, p.quad, path + ": portal node '" + p.node + "'");
  s.set_portals(std::move(portals));
  std::string desc = env ? (env->path().empty() ? std::string("user map") : env->path()) : std::string();
  if (!env) env = default_environment(&desc);
  s.set_environment(std::move(env));
  s.set_environment_description(desc);
  s.commit();
  return s;
}

Scene load_scene(const std::string& name_or_file, const std::string& env_path) {
  std::shared_ptr<const EnvironmentMap> env;
  if (!env_path.empty()) env = std::make_shared<const EnvironmentMap>(EnvironmentMap::load(env_path));
  if (is_builtin_scene(name_or_file)) return make_builtin_scene(name_or_file, env);
  std::error_code ec;
  if (!fs::is_regular_file(name_or_file, ec)) {
    const bool looks_like_file = name_or_file.find('/') != std::string::npos ||
                                 name_or_file.find('.') != std::string::npos;
    if (looks_like_file) throw Error("scene file '" + name_or_file + "' does not exist");
    throw Error("unknown scene '" + name_or_file + "' (built-in scenes: fig1, fig5; or a .json scene file)");
  }
  return load_scene_file(name_or_file, env);
}

}  // namespace envpis::render
