// SPDX-License-Identifier: Apache-2.0
// Internal: bilinear reconstruction of a map's texels, written once for any texel type that adds and
// scales (Rgb for EnvironmentMap::eval, float for the importance table's look-ups). at(x, y) returns
// texel (x, y); (u, v) are texture coordinates in [0,1]^2, texel centres at half-integers.
//   lat-long:    wraps in u (azimuth), clamps in v (the poles).
//   equal-area:  wraps across the square's edges as the sphere does (equal_area_wrap), n x n texels.
#pragma once

#include <algorithm>
#include <cmath>

#include "envpis/equal_area.h"

namespace envpis::detail {

template <class At>
auto bilinear_latlong(const At& at, int w, int h, float u, float v) {
  const float px = u * w - 0.5f, py = v * h - 0.5f;
  const float fx = std::floor(px), fy = std::floor(py);
  const float tx = px - fx, ty = py - fy;
  int x0 = static_cast<int>(fx) % w;
  if (x0 < 0) x0 += w;
  const int x1 = x0 + 1 == w ? 0 : x0 + 1;
  const int y0 = std::clamp(static_cast<int>(fy), 0, h - 1);
  const int y1 = std::clamp(static_cast<int>(fy) + 1, 0, h - 1);
  return (at(x0, y0) * (1 - tx) + at(x1, y0) * tx) * (1 - ty) + (at(x0, y1) * (1 - tx) + at(x1, y1) * tx) * ty;
}

template <class At>
auto bilinear_equal_area(const At& at, int n, float u, float v) {
  const float px = u * n - 0.5f, py = v * n - 0.5f;
  const float fx = std::floor(px), fy = std::floor(py);
  const float tx = px - fx, ty = py - fy;
  decltype(at(0, 0)) acc{};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      int xi = static_cast<int>(fx) + i, yi = static_cast<int>(fy) + j;
      if (!equal_area_wrap(n, xi, yi)) {
        xi = std::clamp(xi, 0, n - 1);
        yi = std::clamp(yi, 0, n - 1);
      }
      acc = acc + at(xi, yi) * ((i ? tx : 1 - tx) * (j ? ty : 1 - ty));
    }
  return acc;
}

}  // namespace envpis::detail
