// SPDX-License-Identifier: Apache-2.0
// Multiple importance sampling weights (Veach 1997) for combining the product (or environment)
// light sample with a BSDF sample: weight of a sample drawn from strategy f with n_f samples, when
// strategy g with n_g samples could also have produced it.
#pragma once

#include <cmath>

namespace envpis {

inline float balance_heuristic(float n_f, float pdf_f, float n_g, float pdf_g) {
  const float f = n_f * pdf_f, g = n_g * pdf_g;
  const float d = f + g;
  return d > 0 && std::isfinite(d) ? f / d : 0.0f;
}

inline float power_heuristic(float n_f, float pdf_f, float n_g, float pdf_g) {
  const float f = n_f * pdf_f, g = n_g * pdf_g;
  if (std::isinf(f)) return 1.0f;  // a delta (or near-delta) strategy takes all the weight
  const float d = f * f + g * g;
  return d > 0 && std::isfinite(d) ? (f * f) / d : 0.0f;
}

}  // namespace envpis
