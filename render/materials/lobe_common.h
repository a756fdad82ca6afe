// SPDX-License-Identifier: Apache-2.0
// Small helpers shared by the lobe implementations in render/materials/ (not part of the API).
#pragma once

#include <cmath>
#include <optional>

#include "render/material.h"
#include "render/materials/microfacet.h"

namespace envpis::render::lobe {

/// Cosine-weighted direction on the upper hemisphere (Shirley-Chiu concentric disk, lifted).
inline Vec3 sample_cosine_hemisphere(Point2 u) {
  const float x = 2.0f * u.x - 1.0f, y = 2.0f * u.y - 1.0f;
  if (x == 0 && y == 0) return {0.0f, 0.0f, 1.0f};
  float r, phi;
  if (std::abs(x) > std::abs(y)) {
    r = x;
    phi = (kPi / 4.0f) * (y / x);
  } else {
    r = y;
    phi = (kPi / 2.0f) - (kPi / 4.0f) * (x / y);
  }
  const float dx = r * std::cos(phi), dy = r * std::sin(phi);
  return {dx, dy, std::sqrt(std::max(0.0f, 1.0f - dx * dx - dy * dy))};
}

/// Density of sample_cosine_hemisphere per solid angle.
inline float cosine_hemisphere_pdf(float cos_theta) { return cos_theta > 0 ? cos_theta * kInvPi : 0.0f; }

inline bool finite(Rgb c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }

/// Builds a BsdfSample from an already evaluated f and pdf; nullopt for a zero or invalid pdf, a
/// degenerate direction or a non-finite value.
inline std::optional<BsdfSample> make_sample(Vec3 wo, Vec3 wi, Rgb f, float pdf) {
  if (!(pdf > 0) || !std::isfinite(pdf) || !microfacet::usable(wi) || !finite(f)) return std::nullopt;
  BsdfSample s;
  s.f = f;
  s.wi = wi;
  s.pdf = pdf;
  s.weight = f * (std::abs(wi.z) / pdf);
  s.transmission = (wo.z > 0) != (wi.z > 0);
  if (!finite(s.weight)) return std::nullopt;
  return s;
}

/// Rgb with every channel clamped to [0, +inf) and NaN replaced by 0 (for user-supplied colours).
inline Rgb sanitize_color(Rgb c) {
  auto f = [](float v) { return std::isfinite(v) && v > 0 ? v : 0.0f; };
  return {f(c.r), f(c.g), f(c.b)};
}

}  // namespace envpis::render::lobe
