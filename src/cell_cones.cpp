// SPDX-License-Identifier: Apache-2.0
#include "cell_cones.h"

#include <algorithm>
#include <cmath>

#include "envpis/equal_area.h"
#include "parallel.h"
#include "shared_per_grid.h"

namespace envpis::detail {

namespace {
// A cone that contains every direction of cell (cx, cy) of a T x T grid on the equal-area square.
Cone bounding_cone(int T, int cx, int cy) {
  constexpr int kEdge = 256;  // boundary samples per cell edge
  constexpr int kInner = 16;  // interior grid for the axis
  const float x0 = float(cx) / T, y0 = float(cy) / T, side = 1.0f / T;
  Cone cone;
  if (T <= 2) {  // cells of a quarter sphere or more: use the whole sphere
    cone.axis = equal_area_square_to_sphere({x0 + 0.5f * side, y0 + 0.5f * side});
    cone.cos_half_angle = -1.0f;
    cone.sin_half_angle = 0.0f;
    return cone;
  }
  double ax = 0, ay = 0, az = 0;
  for (int j = 0; j < kInner; ++j)
    for (int i = 0; i < kInner; ++i) {
      const Vec3 d = equal_area_square_to_sphere({x0 + (i + 0.5f) * side / kInner, y0 + (j + 0.5f) * side / kInner});
      ax += d.x;
      ay += d.y;
      az += d.z;
    }
  const double len = std::sqrt(ax * ax + ay * ay + az * az);
  const Vec3 axis{float(ax / len), float(ay / len), float(az / len)};
  // Walk the boundary; the largest angle from the axis over the cell is on its boundary (the cell is
  // a connected region that does not contain the axis' antipode). Every boundary point is within half
  // the largest gap between consecutive samples of one of them, so that half-gap is added.
  // acos decreases monotonically, so the largest angle is acos of the smallest cosine: one acos per
  // cell instead of one per boundary point, with the same result.
  double min_cos = 1, min_gap_cos = 1;
  Vec3 prev = equal_area_square_to_sphere({x0, y0});
  for (int k = 1; k <= 4 * kEdge; ++k) {
    const int e = (k - 1) / kEdge;
    const float t = float(k - e * kEdge) / kEdge;
    Point2 p;
    switch (e) {
      case 0: p = {x0 + t * side, y0}; break;
      case 1: p = {x0 + side, y0 + t * side}; break;
      case 2: p = {x0 + side - t * side, y0 + side}; break;
      default: p = {x0, y0 + side - t * side}; break;
    }
    const Vec3 d = equal_area_square_to_sphere(p);
    min_cos = std::min(min_cos, std::clamp(double(dot(d, axis)), -1.0, 1.0));
    min_gap_cos = std::min(min_gap_cos, std::clamp(double(dot(d, prev)), -1.0, 1.0));
    prev = d;
  }
  const double max_angle = std::acos(min_cos), max_gap = std::acos(min_gap_cos);
  const double b = std::min(max_angle + 0.5 * max_gap + 1e-4, double(kPi));
  cone.axis = axis;
  cone.cos_half_angle = static_cast<float>(std::cos(b));
  cone.sin_half_angle = static_cast<float>(std::sin(b));
  return cone;
}

std::shared_ptr<const CellCones> compute(int T, int S) {
  const int cells = T * T, per = S * S;
  auto cones = std::make_shared<CellCones>();
  cones->top.assign(static_cast<std::size_t>(cells), Cone{});
  cones->sub.assign(S > 1 ? static_cast<std::size_t>(cells) * per : 0, Cone{});
  parallel_for(0, cells, [&](int begin, int end) {
    for (int c = begin; c < end; ++c) {
      cones->top[static_cast<std::size_t>(c)] = bounding_cone(T, c % T, c / T);
      for (int s = 0; s < per && S > 1; ++s)
        cones->sub[static_cast<std::size_t>(c) * per + s] =
            bounding_cone(T * S, (c % T) * S + s % S, (c / T) * S + s / S);
    }
  });
  return cones;
}

}  // namespace

std::shared_ptr<const CellCones> cell_cones(int T, int S) {
  return shared_per_grid<CellCones>(T, S, [&] { return compute(T, S); });
}

}  // namespace envpis::detail
