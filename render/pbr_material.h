// SPDX-License-Identifier: Apache-2.0
// glTF 2.0 metallic-roughness materials (with KHR_materials_clearcoat, _transmission, _ior and
// _emissive_strength) mapped to the renderer's lobes, optionally textured.
//
// Mapping (per shading point, with c = base colour, m = metallic, alpha = roughness^2 as the glTF
// spec defines the GGX alpha, t = transmission, k = clearcoat, F0 = ((ior - 1) / (ior + 1))^2, which
// is 0.04 at the default IOR 1.5):
//   metal        weight m:                    GGX conductor, Schlick Fresnel with F0 = c
//   specular     weight (1 - m)(1 - t)(1 - k): GGX conductor lobe with Schlick F0 (the dielectric's
//                                              specular reflection)
//   diffuse      weight (1 - m)(1 - t)(1 - k) c (1 - F0): Lambert
//   glass        weight (1 - m) t c:           GGX dielectric (alpha, ior); c tints it
//   coated       weight (1 - m)(1 - t) k:      coated diffuse (base c, coat alpha = clearcoat
//                                              roughness^2, coat IOR 1.5)
// Approximations (docs/scene-format.md): the clear coat covers the dielectric base only (not metal);
// the base colour tints the glass lobe's reflection too; with a textured base colour the coated lobe
// (built white) is tinted as a whole, coat reflection included.
//
// Cost: every lobe tabulates its albedo when it is made (32^3 GGX samples), so lobes are never made
// per shading point. An untextured material is assembled once. A textured one makes its lobes at
// load time: at kRoughnessLevels roughness values when the roughness is textured (the shading point
// takes the nearest level, a roughness step of 1/31) and at the factor otherwise; per shading point
// assemble() only looks up textures and refills a caller-owned Material with shared lobes and colour
// weights (no allocation once the Material's storage has grown). A textured base colour splits the
// metal lobe in two, F0 = 1 weighted c and F0 = 0 weighted 1 - c: Schlick's Fresnel is linear in F0,
// so the sum is the conductor with F0 = c exactly.
#pragma once

#include <memory>
#include <vector>

#include "render/material.h"
#include "render/texture.h"

namespace envpis::render {

struct PbrParams {
  Rgb base_color{1, 1, 1};
  float metallic = 1;
  float roughness = 1;
  float transmission = 0;         ///< KHR_materials_transmission
  float ior = 1.5f;               ///< KHR_materials_ior, in [1, 4]
  float clearcoat = 0;            ///< KHR_materials_clearcoat
  float clearcoat_roughness = 0;
  Rgb emissive{0, 0, 0};          ///< emissiveFactor x KHR_materials_emissive_strength
};

/// The textures multiply the factors (glTF): base colour (sRGB, RGB), metallic-roughness (linear;
/// roughness in G, metallic in B), emissive (sRGB); the normal map (linear, tangent space, +Y up).
struct PbrTextures {
  TextureRef base_color, metallic_roughness, normal, emissive;
  float normal_scale = 1;
};

class PbrMaterial {
 public:
  static constexpr int kRoughnessLevels = 32;

  /// Validates the factors (throws Error naming the offending one) and makes the lobes.
  PbrMaterial(const PbrParams& params, PbrTextures textures);

  /// Whether any texture is present (then assemble() runs per shading point).
  bool textured() const;
  bool transmissive() const { return params_.transmission > 0; }
  const PbrParams& params() const { return params_; }
  const PbrTextures& textures() const { return textures_; }

  /// Fills `out` (cleared first) with the lobes at glTF UV `uv` (ignored when untextured).
  void assemble(Point2 uv, Material* out) const;
  /// Emitted radiance at uv.
  Rgb emission(Point2 uv) const;
  bool has_normal_map() const { return bool(textures_.normal); }
  /// The normal-mapped shading normal: ns (unit) and the tangent dpdu (along +u) span the tangent
  /// frame; bitangent_sign is +1 when the bitangent is cross(ns, tangent) (glTF's usual handedness)
  /// and -1 for mirrored UVs. Returns ns when the map or the frame is degenerate.
  Vec3 normal_mapped(Point2 uv, Vec3 ns, Vec3 dpdu, float bitangent_sign) const;

 private:
  struct Level {
    std::shared_ptr<const Lobe> metal, metal_edge, specular, glass;
  };
  const Level& level(float roughness) const;
  PbrParams params_;
  PbrTextures textures_;
  float f0_dielectric_ = 0.04f;
  std::vector<Level> levels_;  // kRoughnessLevels entries with a roughness texture, else 1
  std::shared_ptr<const Lobe> diffuse_, coat_;
};

}  // namespace envpis::render
