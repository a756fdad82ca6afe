// SPDX-License-Identifier: Apache-2.0
// Path regularization: the three switches of Cycles' Light Paths panel, with Cycles' semantics, so a
// Cycles render can be set the same way (docs/cli.md, "Path regularization"). All off by default, and
// then the integrator's images are bit-identical to an unregularized build.
//
//   clamp    (Cycles' sample_clamp_direct / sample_clamp_indirect). Each contribution a path adds to
//            the pixel (one light sample, one BSDF sample that escapes, one emission hit) is scaled
//            by one common factor, so that the sum of its three |channels| is at most 3 X: the mean
//            of the channels is clamped to X, the hue is kept. Cycles stores 3 X and compares the
//            channel sum (scene/integrator.cpp, film_clamp_light). "Direct" is what reaches the
//            camera after at most one surface interaction: a light or BSDF sample of the first hit,
//            emission of the first two hits, the environment seen by the camera; the rest is
//            indirect. 0 = off.
//   caustics (Cycles' caustics_reflective / caustics_refractive). Off, a vertex that a diffuse BSDF
//            sample reached (Cycles' PATH_RAY_DIFFUSE: the last bounce was diffuse) loses its glossy
//            reflection (conductors, the dielectric's reflection, coats) or its glossy refraction (the
//            dielectric's transmission), for its light sample and its BSDF sample alike: a diffuse
//            floor under a glass sphere then gets no light through the sphere.
//   filter glossy (Cycles' blur_glossy, X > 0). At every vertex after the first, with p_min the
//            smallest density of the path's BSDF samples so far (solid angle, the whole material's
//            mixture pdf), every GGX lobe's alpha is raised to at least 0.5 sqrt(1 - p_min / X) when
//            p_min < X (surface_shader_prepare_closures, bsdf_blur). The widened lobe is the one the
//            vertex samples, evaluates and hands to the product proxy. 0 = off.
#pragma once

#include <cmath>
#include <limits>

#include "render/material.h"

namespace envpis::render {

struct RegularizationOptions {
  float clamp_direct = 0;          ///< >= 0; 0 = off
  float clamp_indirect = 0;        ///< >= 0; 0 = off
  bool caustics_reflective = true;
  bool caustics_refractive = true;
  float filter_glossy = 0;         ///< >= 0; 0 = off
  /// Whether any switch is on (the images differ from the unregularized ones).
  bool active() const {
    return clamp_direct > 0 || clamp_indirect > 0 || !caustics_reflective || !caustics_refractive || filter_glossy > 0;
  }
};

/// Throws Error naming the value for a negative or non-finite clamp or filter.
void validate(const RegularizationOptions& o);

/// `--caustics` as text: "reflective,refractive" (both on, the default), "reflective", "refractive" or
/// "none"; and back.
void parse_caustics(const std::string& s, RegularizationOptions* o);
std::string caustics_string(const RegularizationOptions& o);

/// c scaled so that |r| + |g| + |b| <= 3 limit (Cycles' clamp); limit 0 leaves c as it is.
inline Rgb clamp_contribution(Rgb c, float limit) {
  if (!(limit > 0)) return c;
  const float sum = std::fabs(c.r) + std::fabs(c.g) + std::fabs(c.b);
  return sum > 3 * limit ? c * (3 * limit / sum) : c;
}

/// Filter Glossy's roughness floor after BSDF samples whose smallest density is min_pdf; 0 when the
/// filter is off or min_pdf >= filter_glossy.
inline float filter_glossy_alpha(float filter_glossy, float min_pdf) {
  if (!(filter_glossy > 0) || !(min_pdf < filter_glossy)) return 0.0f;
  return 0.5f * std::sqrt(1.0f - min_pdf / filter_glossy);
}

/// One path's regularization state, carried from vertex to vertex by the integrator.
class PathRegularizer {
 public:
  explicit PathRegularizer(const RegularizationOptions& o) : o_(o), on_(o.active()) {}

  /// A contribution, clamped as direct light (at most one surface interaction) or indirect.
  Rgb clamp(Rgb c, bool direct) const { return on_ ? clamp_contribution(c, direct ? o_.clamp_direct : o_.clamp_indirect) : c; }

  /// The BSDF this vertex uses: `bsdf` itself when nothing applies, else `scratch` refilled with its
  /// lobes filtered (no allocation for unchanged lobes).
  const Material& material(const Material& bsdf, Material* scratch) const {
    const LobeFilter f = filter();
    if (!(f.min_alpha > 0) && f.reflection && f.refraction) return bsdf;
    bsdf.filter_into(f, scratch);
    return *scratch;
  }

  /// Records the BSDF sample that continues the path.
  void bounce(const BsdfSample& s) {
    min_pdf_ = std::fmin(min_pdf_, s.pdf);
    after_diffuse_ = s.diffuse;
  }

  /// What the next vertex keeps of its lobes.
  LobeFilter filter() const {
    LobeFilter f;
    if (!on_) return f;
    f.min_alpha = filter_glossy_alpha(o_.filter_glossy, min_pdf_);
    f.reflection = o_.caustics_reflective || !after_diffuse_;
    f.refraction = o_.caustics_refractive || !after_diffuse_;
    return f;
  }

 private:
  RegularizationOptions o_;
  bool on_;
  float min_pdf_ = std::numeric_limits<float>::infinity();
  bool after_diffuse_ = false;  ///< the last BSDF sample was diffuse
};

}  // namespace envpis::render
