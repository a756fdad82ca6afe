// SPDX-License-Identifier: Apache-2.0
#include "render/pbr_material.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "render/math.h"

namespace envpis::render {

namespace {

void check_unit(float v, const char* name) {
  if (!(v >= 0 && v <= 1)) throw Error(std::string("material: ") + name + " must be in [0, 1], got " + std::to_string(v));
}

Rgb clamp01(Rgb c) { return {std::clamp(c.r, 0.0f, 1.0f), std::clamp(c.g, 0.0f, 1.0f), std::clamp(c.b, 0.0f, 1.0f)}; }

}  // namespace

PbrMaterial::PbrMaterial(const PbrParams& p, PbrTextures textures) : params_(p), textures_(std::move(textures)) {
  for (float c : {p.base_color.r, p.base_color.g, p.base_color.b}) check_unit(c, "base colour");
  check_unit(p.metallic, "metallic");
  check_unit(p.roughness, "roughness");
  check_unit(p.transmission, "transmission");
  check_unit(p.clearcoat, "clearcoat");
  check_unit(p.clearcoat_roughness, "clearcoat roughness");
  if (!(p.ior >= 1 && p.ior <= 4)) throw Error("material: ior must be in [1, 4], got " + std::to_string(p.ior));
  for (float c : {p.emissive.r, p.emissive.g, p.emissive.b})
    if (!(c >= 0 && std::isfinite(c))) throw Error("material: emissive must be finite and >= 0");
  if (!std::isfinite(textures_.normal_scale)) throw Error("material: normal scale must be finite");
  const float r = (p.ior - 1) / (p.ior + 1);
  f0_dielectric_ = r * r;

  const bool tinted_metal = bool(textures_.base_color);
  const Rgb metal_f0 = tinted_metal ? Rgb{1, 1, 1} : p.base_color;
  const bool textured_roughness = bool(textures_.metallic_roughness);
  const int n = textured_roughness ? kRoughnessLevels : 1;
  // Only the lobes some shading point can use: a metallic texture scales the factor down, never up.
  const bool any_metal = p.metallic > 0, any_dielectric = p.metallic < 1 || textured_roughness;
  for (int k = 0; k < n; ++k) {
    const float rough = textured_roughness ? float(k) / float(n - 1) : p.roughness;
    const float alpha = rough * rough;
    Level l;
    if (any_metal) {
      l.metal = make_conductor_reflectance(alpha, metal_f0);
      if (tinted_metal) l.metal_edge = make_conductor_reflectance(alpha, {0, 0, 0});
    }
    if (any_dielectric && p.transmission < 1 && p.clearcoat < 1) l.specular = make_conductor_reflectance(alpha, {f0_dielectric_, f0_dielectric_, f0_dielectric_});
    if (any_dielectric && p.transmission > 0) l.glass = make_dielectric(alpha, p.ior);
    levels_.push_back(std::move(l));
  }
  if (any_dielectric && p.transmission < 1 && p.clearcoat < 1) diffuse_ = make_lambert({1, 1, 1});
  if (any_dielectric && p.transmission < 1 && p.clearcoat > 0) {
    const float ca = p.clearcoat_roughness * p.clearcoat_roughness;
    coat_ = make_coated_diffuse(textures_.base_color ? Rgb{1, 1, 1} : p.base_color, ca, 1.5f);
  }
}

bool PbrMaterial::textured() const {
  return textures_.base_color || textures_.metallic_roughness || textures_.normal || textures_.emissive;
}

const PbrMaterial::Level& PbrMaterial::level(float roughness) const {
  if (levels_.size() == 1) return levels_[0];
  const float x = std::clamp(roughness, 0.0f, 1.0f) * float(levels_.size() - 1);
  return levels_[static_cast<std::size_t>(x + 0.5f)];
}

void PbrMaterial::assemble(Point2 uv, Material* out) const {
  out->clear_lobes();
  Rgb tint{1, 1, 1};  // the base colour's texture (its factor is inside the lobes or below)
  Rgb c = params_.base_color;
  float m = params_.metallic, rough = params_.roughness;
  if (textures_.base_color) {
    tint = clamp01(textures_.base_color.sample(uv).rgb());
    c = c * tint;
  }
  if (textures_.metallic_roughness) {
    const Rgba mr = textures_.metallic_roughness.sample(uv);
    rough = std::clamp(rough * mr.g, 0.0f, 1.0f);
    m = std::clamp(m * mr.b, 0.0f, 1.0f);
  }
  const Level& l = level(rough);
  const float t = params_.transmission, k = params_.clearcoat, d = 1 - m;
  if (l.metal) {
    if (l.metal_edge) {
      out->add(l.metal, c * m);
      out->add(l.metal_edge, Rgb{1 - c.r, 1 - c.g, 1 - c.b} * m);
    } else {
      out->add(l.metal, m);
    }
  }
  if (l.specular) out->add(l.specular, d * (1 - t) * (1 - k));
  if (diffuse_) out->add(diffuse_, c * (d * (1 - t) * (1 - k) * (1 - f0_dielectric_)));
  if (l.glass) out->add(l.glass, c * (d * t));
  if (coat_) out->add(coat_, (textures_.base_color ? tint * params_.base_color : Rgb{1, 1, 1}) * (d * (1 - t) * k));
}

Rgb PbrMaterial::emission(Point2 uv) const {
  if (!textures_.emissive) return params_.emissive;
  return params_.emissive * textures_.emissive.sample(uv).rgb();
}

Vec3 PbrMaterial::normal_mapped(Point2 uv, Vec3 ns, Vec3 dpdu, float bitangent_sign) const {
  if (!textures_.normal) return ns;
  const Rgba px = textures_.normal.sample(uv);
  const float s = textures_.normal_scale;
  const Vec3 nt{(2 * px.r - 1) * s, (2 * px.g - 1) * s, 2 * px.b - 1};
  Vec3 tangent = dpdu - ns * dot(ns, dpdu);
  if (!is_valid_direction(tangent) || !is_valid_direction(nt)) return ns;
  tangent = normalize(tangent);
  const Vec3 bitangent = cross(ns, tangent) * bitangent_sign;
  const Vec3 n = tangent * nt.x + bitangent * nt.y + ns * nt.z;
  return is_valid_direction(n) ? normalize(n) : ns;
}

}  // namespace envpis::render
