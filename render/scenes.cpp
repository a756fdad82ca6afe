#include "render/scenes.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace envpis::render {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Environments

EnvironmentMap make_procedural_sky(const SkyOptions& o) {
  if (o.width < 4 || o.height < 2 || o.width > 16384 || o.height > 8192) throw Error("sky: invalid resolution");
  if (!(o.sun_radius > 0 && o.sun_radius < 90)) throw Error("sky: sun radius must be in (0, 90) degrees");
  if (!(o.sun_radiance >= 0) || !(o.sky_radiance >= 0) || !(o.ground_radiance >= 0))
    throw Error("sky: radiances must be >= 0");
  const float el = o.sun_elevation * kPi / 180.0f, az = o.sun_azimuth * kPi / 180.0f;
  const Vec3 sun{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  const float cos_r = std::cos(o.sun_radius * kPi / 180.0f);
  const float cos_soft = std::cos(0.85f * o.sun_radius * kPi / 180.0f);
  const Rgb zenith{0.18f, 0.32f, 0.70f}, horizon{0.95f, 0.90f, 0.85f}, sun_color{1.0f, 0.92f, 0.80f};
  auto radiance = [&](Vec3 d) -> Rgb {
    Rgb c;
    if (d.z >= 0) {
      const float h = std::pow(1.0f - d.z, 3.0f);
      c = (zenith * (1.0f - h) + horizon * h) * o.sky_radiance;
    } else {
      c = Rgb{1.0f, 0.95f, 0.9f} * o.ground_radiance;
    }
    const float cs = dot(d, sun);
    if (cs > cos_r) {
      const float edge = cs >= cos_soft ? 1.0f : (cs - cos_r) / (cos_soft - cos_r);  // soft limb
      c = c + sun_color * (o.sun_radiance * edge);
    }
    return c;
  };
  constexpr int S = 4;  // supersampling per texel
  std::vector<float> px(static_cast<std::size_t>(o.width) * o.height * 3);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      Rgb acc;
      for (int sy = 0; sy < S; ++sy)
        for (int sx = 0; sx < S; ++sx) {
          const Point2 uv{(x + (sx + 0.5f) / S) / o.width, (y + (sy + 0.5f) / S) / o.height};
          acc = acc + radiance(latlong_to_direction(uv));
        }
      float* p = &px[(static_cast<std::size_t>(y) * o.width + x) * 3];
      p[0] = acc.r / (S * S);
      p[1] = acc.g / (S * S);
      p[2] = acc.b / (S * S);
    }
  EnvironmentMapOptions mo;
  mo.layout = MapLayout::LatLong;
  // The texels were computed at latlong_to_direction(uv), the map-space direction, which is the world
  // direction exactly for a Legacy map without rotation.
  mo.orientation = LatLongOrientation::Legacy;
  return EnvironmentMap::from_pixels(o.width, o.height, std::move(px), mo);
}

EnvironmentMap make_constant_environment(Rgb radiance, int width, int height) {
  std::vector<float> px(static_cast<std::size_t>(width) * height * 3);
  for (std::size_t i = 0; i < px.size(); i += 3) {
    px[i] = radiance.r;
    px[i + 1] = radiance.g;
    px[i + 2] = radiance.b;
  }
  EnvironmentMapOptions mo;
  mo.layout = MapLayout::LatLong;
  return EnvironmentMap::from_pixels(width, height, std::move(px), mo);
}

std::shared_ptr<const EnvironmentMap> default_environment(std::string* description) {
  const std::string sunset = std::string(kBlenderWorldDir) + "/sunset.exr";
  std::error_code ec;
  if (fs::exists(sunset, ec)) {
    if (description) *description = sunset;
    return std::make_shared<const EnvironmentMap>(EnvironmentMap::load(sunset));
  }
  if (description) *description = "procedural sky (no " + sunset + ")";
  return std::make_shared<const EnvironmentMap>(make_procedural_sky());
}

// ---------------------------------------------------------------------------------------------
// Procedural meshes

TriangleMesh make_torus_knot(int p, int q, float major, float minor, float tube, int segments, int sides) {
  if (segments < 3 || sides < 3) throw Error("torus knot: needs at least 3 segments and 3 sides");
  TriangleMesh m;
  m.positions.reserve(static_cast<std::size_t>(segments) * sides);
  m.normals.reserve(m.positions.capacity());
  const float fp = float(p), fq = float(q);
  for (int i = 0; i < segments; ++i) {
    const float t = 2.0f * kPi * float(i) / float(segments);
    const float cq = std::cos(fq * t), sq = std::sin(fq * t), cp = std::cos(fp * t), sp = std::sin(fp * t);
    const float r = major + minor * cq, r1 = -minor * fq * sq, r2 = -minor * fq * fq * cq;
    const Vec3 c{r * cp, r * sp, minor * sq};
    const Vec3 d1{r1 * cp - fp * r * sp, r1 * sp + fp * r * cp, minor * fq * cq};
    const Vec3 d2{r2 * cp - 2 * fp * r1 * sp - fp * fp * r * cp, r2 * sp + 2 * fp * r1 * cp - fp * fp * r * sp,
                  -minor * fq * fq * sq};
    const Vec3 T = normalize(d1);
    const Vec3 B = normalize(cross(d1, d2));  // Frenet frame: periodic, so the tube closes exactly
    const Vec3 N = cross(B, T);
    for (int j = 0; j < sides; ++j) {
      const float a = 2.0f * kPi * float(j) / float(sides);
      const Vec3 n = N * std::cos(a) + B * std::sin(a);
      m.positions.push_back(c + n * tube);
      m.normals.push_back(n);
    }
  }
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      const std::uint32_t i1 = (i + 1) % segments, j1 = (j + 1) % sides;
      const std::uint32_t a = i * sides + j, b = i1 * sides + j, c = i1 * sides + j1, d = i * sides + j1;
      // counter-clockwise seen from outside (cross(T, n) ordering)
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
  // Make the winding agree with the outward normals.
  const std::uint32_t* t0 = m.indices.data();
  const Vec3 fn = cross(m.positions[t0[1]] - m.positions[t0[0]], m.positions[t0[2]] - m.positions[t0[0]]);
  if (dot(fn, m.normals[t0[0]]) < 0)
    for (std::size_t k = 0; k < m.indices.size(); k += 3) std::swap(m.indices[k + 1], m.indices[k + 2]);
  return m;
}

TriangleMesh make_quad(Vec3 c, float hx, float hy) {
  TriangleMesh m;
  m.positions = {c + Vec3{-hx, -hy, 0}, c + Vec3{hx, -hy, 0}, c + Vec3{hx, hy, 0}, c + Vec3{-hx, hy, 0}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// ---------------------------------------------------------------------------------------------
// Built-in scenes

const std::vector<std::string>& builtin_scene_names() {
  static const std::vector<std::string> names{"fig1", "fig5"};
  return names;
}

bool is_builtin_scene(const std::string& name) {
  const auto& n = builtin_scene_names();
  return std::find(n.begin(), n.end(), name) != n.end();
}

const std::vector<std::string>& fig1_sphere_names() {
  static const std::vector<std::string> names{"conductor-0.02", "conductor-0.05", "conductor-0.1",
                                              "conductor-0.2",  "conductor-0.3",  "conductor-0.5",
                                              "diffuse",        "glass"};
  return names;
}

namespace {

Material single(std::shared_ptr<const Lobe> lobe) {
  Material m;
  m.add(std::move(lobe), 1.0f);
  return m;
}

Scene build_fig1(std::shared_ptr<const EnvironmentMap> env, std::string env_desc) {
  Scene s;
  const float roughness[6] = {0.02f, 0.05f, 0.1f, 0.2f, 0.3f, 0.5f};
  const Rgb metal{0.9f, 0.9f, 0.9f};
  const auto& names = fig1_sphere_names();
  for (int i = 0; i < 6; ++i)
    s.add_material(names[i], single(make_conductor_reflectance(roughness[i], metal)), false);
  s.add_material("diffuse", single(make_lambert({0.8f, 0.8f, 0.8f})), false);
  s.add_material("glass", single(make_dielectric(0.2f, 1.5f)), true);
  const float spacing = 2.3f;
  for (int i = 0; i < 8; ++i) s.add_sphere(names[i], {(float(i) - 3.5f) * spacing, 0.0f, 0.0f}, 1.0f, i);
  CameraSpec cam;
  cam.from = {0, -40, 0};
  cam.to = {0, 0, 0};
  cam.up = {0, 0, 1};
  cam.vfov_degrees = 4.8f;
  cam.width = 768;
  cam.height = 128;
  s.set_camera(cam);
  s.set_environment(std::move(env));
  s.set_environment_description(std::move(env_desc));
  s.commit();
  return s;
}

Scene build_fig5(std::shared_ptr<const EnvironmentMap> env, std::string env_desc) {
  Scene s;
  // Gold: complex IOR at ~650 / 550 / 450 nm.
  s.add_material("gold", single(make_conductor(0.25f, {0.143f, 0.374f, 1.442f}, {3.983f, 2.386f, 1.603f})), false);
  s.add_material("ground", single(make_lambert({0.12f, 0.12f, 0.12f})), false);
  TriangleMesh knot = make_torus_knot(2, 3, 2.0f, 0.9f, 0.42f, 600, 32);
  for (Vec3& p : knot.positions) p = p + Vec3{0, 0, 1.36f};  // lowest point 0.04 above the ground
  s.add_mesh("knot", std::move(knot), 0);
  s.add_mesh("ground", make_quad({0, 0, 0}, 12.0f, 12.0f), 1);
  CameraSpec cam;
  cam.from = {0.0f, -9.0f, 4.6f};
  cam.to = {0.0f, 0.0f, 1.2f};
  cam.up = {0, 0, 1};
  cam.vfov_degrees = 34.0f;
  cam.width = 640;
  cam.height = 360;
  s.set_camera(cam);
  s.set_environment(std::move(env));
  s.set_environment_description(std::move(env_desc));
  s.commit();
  return s;
}

}  // namespace

Scene make_builtin_scene(const std::string& name, std::shared_ptr<const EnvironmentMap> env) {
  std::string desc = env ? (env->path().empty() ? std::string("user map") : env->path()) : std::string();
  if (name == "fig1") {
    if (!env) env = default_environment(&desc);
    return build_fig1(std::move(env), desc);
  }
  if (name == "fig5") {
    if (!env) {
      const std::string studio = std::string(kBlenderWorldDir) + "/studio.exr";
      std::error_code ec;
      if (fs::exists(studio, ec)) {
        env = std::make_shared<const EnvironmentMap>(EnvironmentMap::load(studio));
        desc = studio;
      } else {
        env = default_environment(&desc);
      }
    }
    return build_fig5(std::move(env), desc);
  }
  throw Error("unknown scene '" + name + "' (built-in scenes: fig1, fig5; or a .json scene file)");
}

// ---------------------------------------------------------------------------------------------
// Scene files

namespace {

/// Typed access to a JSON object with errors that name the file and the field's path.
class Fields {
 public:
  Fields(const json& j, std::string path, const std::string* file) : j_(j), path_(std::move(path)), file_(file) {
    if (!j.is_object()) fail("expected an object");
  }

  [[noreturn]] void fail(const std::string& what) const { fail_at(path_, what); }
  [[noreturn]] void fail_at(const std::string& path, const std::string& what) const {
    throw Error(*file_ + ": " + (path.empty() ? std::string("(top level)") : path) + ": " + what);
  }
  std::string sub(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  bool has(const std::string& key) const {
    used_.insert(key);
    return j_.contains(key);
  }
  const json& get(const std::string& key) const {
    used_.insert(key);
    if (!j_.contains(key)) fail("missing field '" + key + "'");
    return j_.at(key);
  }
  Fields object(const std::string& key) const { return Fields(get(key), sub(key), file_); }

  float number(const std::string& key) const {
    const json& v = get(key);
    if (!v.is_number()) fail_at(sub(key), "expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail_at(sub(key), "expected a finite number");
    return static_cast<float>(d);
  }
  float number(const std::string& key, float def) const { return has(key) ? number(key) : def; }
  float number_in(const std::string& key, float def, float lo, float hi) const {
    const float v = number(key, def);
    if (!(v >= lo && v <= hi))
      fail_at(sub(key), "must be in [" + fmt(lo) + ", " + fmt(hi) + "], got " + fmt(v));
    return v;
  }
  int integer(const std::string& key, int def, int lo, int hi) const {
    if (!has(key)) return def;
    const json& v = get(key);
    if (!v.is_number_integer()) fail_at(sub(key), "expected an integer");
    const long long x = v.get<long long>();
    if (x < lo || x > hi) fail_at(sub(key), "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(x);
  }
  bool boolean(const std::string& key, bool def) const {
    if (!has(key)) return def;
    const json& v = get(key);
    if (!v.is_boolean()) fail_at(sub(key), "expected true or false");
    return v.get<bool>();
  }
  std::string string(const std::string& key) const {
    const json& v = get(key);
    if (!v.is_string()) fail_at(sub(key), "expected a string");
    return v.get<std::string>();
  }
  std::string string(const std::string& key, const std::string& def) const { return has(key) ? string(key) : def; }
  Vec3 vec3(const std::string& key) const {
    const json& v = get(key);
    if (!v.is_array() || v.size() != 3) fail_at(sub(key), "expected an array of 3 numbers");
    float c[3];
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail_at(sub(key), "expected an array of 3 numbers");
      c[i] = v[i].get<float>();
    }
    return {c[0], c[1], c[2]};
  }
  Vec3 vec3(const std::string& key, Vec3 def) const { return has(key) ? vec3(key) : def; }
  /// A colour: a number (grey) or [r, g, b], each in [lo, hi].
  Rgb color(const std::string& key, Rgb def, float lo = 0.0f, float hi = 1.0f) const {
    if (!has(key)) return def;
    const json& v = get(key);
    Rgb c;
    if (v.is_number()) {
      const float g = v.get<float>();
      c = {g, g, g};
    } else if (v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()) {
      c = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    } else {
      fail_at(sub(key), "expected a number or an array of 3 numbers");
    }
    for (float x : {c.r, c.g, c.b})
      if (!(x >= lo && x <= hi)) fail_at(sub(key), "components must be in [" + fmt(lo) + ", " + fmt(hi) + "]");
    return c;
  }
  /// Rejects fields that were never read (typos).
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) fail("unknown field '" + it.key() + "'");
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }

 private:
  static std::string fmt(float v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }
  const json& j_;
  std::string path_;
  const std::string* file_;
  mutable std::set<std::string> used_;
};

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
                                 "' (expected diffuse, translucent, conductor, dielectric, coated-diffuse or mix)");
  }
  return out;
}

SceneMaterial parse_material(const Fields& f, const std::string& name) {
  SceneMaterial m;
  m.name = name;
  const std::string type = f.string("type");
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

void apply_transform(TriangleMesh& m, const Fields& f) {
  Vec3 scale{1, 1, 1};
  if (f.has("scale")) {
    const json& s = f.get("scale");
    if (s.is_number()) {
      const float k = f.number("scale");
      scale = {k, k, k};
    } else {
      scale = f.vec3("scale");
    }
    if (!(scale.x != 0 && scale.y != 0 && scale.z != 0)) f.fail_at(f.sub("scale"), "must be non-zero");
  }
  const Mat3 R = euler_xyz(f.vec3("rotate", {0, 0, 0}));
  const Vec3 t = f.vec3("translate", {0, 0, 0});
  for (Vec3& p : m.positions) p = R * mul(p, scale) + t;
  const Vec3 inv{1 / scale.x, 1 / scale.y, 1 / scale.z};
  for (Vec3& n : m.normals) n = R * mul(n, inv);
  if (scale.x * scale.y * scale.z < 0)  // a mirroring transform flips the winding
    for (std::size_t k = 0; k < m.indices.size(); k += 3) std::swap(m.indices[k + 1], m.indices[k + 2]);
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
  std::string file = f.string("file");
  if (fs::path(file).is_relative()) file = (dir / file).string();
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

}  // namespace

Scene load_scene_file(const std::string& path, std::shared_ptr<const EnvironmentMap> env) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open scene file '" + path + "'");
  json j;
  try {
    j = json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    throw Error(path + ": invalid JSON: " + e.what());
  }
  const fs::path dir = fs::path(path).parent_path();
  Fields top(j, "", &path);
  Scene s;

  // camera
  Fields cf = top.object("camera");
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
  try {
    Camera check(cam, cam.width, cam.height);
  } catch (const Error& e) {
    top.fail_at("camera", e.what());
  }
  s.set_camera(cam);

  // environment (optional when overridden)
  std::string desc;
  if (top.has("environment") && !env)  // an override (--env) replaces the file's environment
    env = parse_environment(top.object("environment"), dir, &desc);
  if (!env) env = default_environment(&desc);
  else if (desc.empty()) desc = env->path().empty() ? "user map" : env->path();
  s.set_environment(env);
  s.set_environment_description(desc);

  // materials
  (void)top.object("materials");  // must be an object
  const json& mats = top.get("materials");
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    Fields f(it.value(), "materials." + it.key(), &path);
    SceneMaterial m = parse_material(f, it.key());
    s.add_material(m.name, std::move(m.bsdf), m.transmissive);
  }
  if (s.material_count() == 0) top.fail_at("materials", "needs at least one material");

  // objects
  const json& objs = top.get("objects");
  if (!objs.is_array() || objs.empty()) top.fail_at("objects", "expected a non-empty array");
  for (std::size_t i = 0; i < objs.size(); ++i) {
    Fields f(objs[i], "objects[" + std::to_string(i) + "]", &path);
    const std::string type = f.string("type");
    const std::string mname = f.string("material");
    const int mat = s.find_material(mname);
    if (mat < 0) f.fail_at(f.sub("material"), "unknown material '" + mname + "'");
    std::string name = f.string("name", type + "-" + std::to_string(i));
    if (type == "sphere") {
      const Vec3 c = f.vec3("center");
      const float r = f.number("radius");
      if (!(r > 0)) f.fail_at(f.sub("radius"), "must be positive");
      f.finish();
      s.add_sphere(name, c, r, mat);
    } else if (type == "mesh" || type == "torus-knot" || type == "quad") {
      TriangleMesh m;
      if (type == "mesh") {
        std::string file = f.string("file");
        if (fs::path(file).is_relative()) file = (dir / file).string();
        m = load_mesh_file(file, f.boolean("smooth", true), f);
      } else if (type == "torus-knot") {
        m = make_torus_knot(f.integer("p", 2, 1, 32), f.integer("q", 3, 1, 32), f.number_in("major", 2.0f, 0, 1e6f),
                            f.number_in("minor", 0.9f, 0, 1e6f), f.number_in("tube", 0.42f, 1e-6f, 1e6f),
                            f.integer("segments", 600, 3, 100000), f.integer("sides", 32, 3, 4096));
      } else {
        const float size = f.number_in("size", 10.0f, 1e-6f, 1e9f);
        m = make_quad({0, 0, 0}, 0.5f * size, 0.5f * size);
      }
      apply_transform(m, f);
      f.finish();
      s.add_mesh(name, std::move(m), mat);
    } else {
      f.fail_at(f.sub("type"), "unknown object type '" + type + "' (expected sphere, mesh, torus-knot or quad)");
    }
  }
  // Closed-surface proxy (docs/proxy.md): on unless the file says otherwise.
  s.set_proxy_closed_surfaces(top.boolean("closed_surfaces", true));
  top.finish();
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
