// SPDX-License-Identifier: Apache-2.0
// The built-in scenes, environments and procedural meshes of render/scenes.h (scene files:
// render/scene_file.cpp).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "render/scenes.h"

namespace envpis::render {

namespace fs = std::filesystem;

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
  m.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};  // glTF convention: v = 0 at the +Y edge
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
  s.set_camera(look_at({0, -40, 0}, {0, 0, 0}, 4.8f, 768, 128));
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
  s.set_camera(look_at({0.0f, -9.0f, 4.6f}, {0.0f, 0.0f, 1.2f}, 34.0f, 640, 360));
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

}  // namespace envpis::render
