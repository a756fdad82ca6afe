// SPDX-License-Identifier: Apache-2.0
// The table's peak bound as it was computed before 2026-12-02 (src/texel_peak.cpp at 1d3bd5d: a max tree
// per map row, a separate array of peaks), kept as the reference that the faster build must
// reproduce bit for bit (tests/test_texel_peak.cpp). Only the namespace and the row loop (one row per
// TBB task instead of the library's parallel_for) differ, and the footprint of a texel (the margin
// rule) is the library's own, so that the reference follows a change of the bound itself.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "envpis/envpis.h"
#include "texel_peak.h"

namespace envpis::test::old_peak {

namespace detail_old {

// Range maximum over the columns of each row: one bottom-up max tree per row (leaves padded to a power
// of two), so a query over any column range costs O(log width).
class RowMaxTree {
 public:
  RowMaxTree(const std::vector<float>& lum, int w, int h) : w_(w), leaves_(1) {
    while (leaves_ < w) leaves_ *= 2;
    tree_.assign(static_cast<std::size_t>(h) * 2 * leaves_, 0.0f);
    for (int y = 0; y < h; ++y) {
      float* t = row(y);
      std::copy_n(&lum[static_cast<std::size_t>(y) * w], w, t + leaves_);
      for (int i = leaves_ - 1; i >= 1; --i) t[i] = std::max(t[2 * i], t[2 * i + 1]);
    }
  }
  /// Max over columns [a, b] of row y, 0 <= a <= b < width.
  float query(int y, int a, int b) const {
    const float* t = row(y);
    float m = 0;
    for (a += leaves_, b += leaves_ + 1; a < b; a >>= 1, b >>= 1) {
      if (a & 1) m = std::max(m, t[a++]);
      if (b & 1) m = std::max(m, t[--b]);
    }
    return m;
  }
  /// Max over columns [a, b] taken modulo the width (a range that crosses the seam wraps around).
  float query_wrapped(int y, int a, int b) const {
    if (b - a + 1 >= w_) return query(y, 0, w_ - 1);
    a = ((a % w_) + w_) % w_;
    b = ((b % w_) + w_) % w_;
    return a <= b ? query(y, a, b) : std::max(query(y, a, w_ - 1), query(y, 0, b));
  }

 private:
  float* row(int y) { return &tree_[static_cast<std::size_t>(y) * 2 * leaves_]; }
  const float* row(int y) const { return &tree_[static_cast<std::size_t>(y) * 2 * leaves_]; }
  int w_, leaves_;
  std::vector<float> tree_;
};

// The outline of a texel: its corners and edge midpoints, going round.
constexpr int kOutline = 8;

// Whether the outline's azimuths (in turns, [0, 1)) wind once around a pole: the texel contains it.
// A step of nearly half a turn means the pole lies on the outline, between two of its points.
bool winds_around_pole(const float* us) {
  float turns = 0;
  for (int k = 0; k < kOutline; ++k) {
    float d = us[(k + 1) % kOutline] - us[k];
    d -= std::round(d);
    if (std::fabs(d) > 0.4f) return true;
    turns += d;
  }
  return std::fabs(turns) > 0.5f;
}

// Map coordinates (u, v) and map-space z of points along one horizontal line of the table.
struct Line {
  std::vector<float> u, v, z;
};

// `count` points (i * step, y) of the equal-area square, i = 0 .. count - 1, in the map's coordinates.
void map_line(const EnvironmentMap& map, bool latlong, float y, int count, float step, Line& out) {
  std::vector<float> su(count), sv(count, y), dx(count), dy(count), dz(count);
  for (int i = 0; i < count; ++i) su[i] = std::min(1.0f, float(i) * step);
  equal_area_square_to_sphere(static_cast<std::size_t>(count), su.data(), sv.data(), dx.data(), dy.data(), dz.data());
  out.u.resize(count), out.v.resize(count), out.z.resize(count);
  for (int i = 0; i < count; ++i) {
    const Vec3 md = map.to_map({dx[i], dy[i], dz[i]});
    const Point2 p = latlong ? direction_to_latlong(md) : equal_area_sphere_to_square(md);
    out.u[i] = p.x, out.v[i] = p.y, out.z[i] = md.z;
  }
}

}  // namespace detail_old

using namespace detail_old;

inline std::vector<float> texel_peaks(const EnvironmentMap& map, const std::vector<float>& lum, int N) {
  const int w = map.width(), h = map.height();
  const bool latlong = map.layout() != MapLayout::EqualArea;
  const bool nearest = map.filter() == MapFilter::Nearest;
  const RowMaxTree tree(lum, w, h);
  const float map_max = *std::max_element(lum.begin(), lum.end());
  // An outline point this close to a lat-long pole (a thousandth of a texel side) has no usable azimuth.
  const float pole_z = std::cos(1e-3f * std::sqrt(4.0f * kPi) / float(N));
  std::vector<float> peaks(static_cast<std::size_t>(N) * N, 0.0f);
  const float inv_n = 1.0f / float(N);

  tbb::parallel_for(0, N, [&](int row) {
    const int row_begin = row, row_end = row + 1;
    // Outline points are shared: the corners and horizontal midpoints lie on the lines y and y + 1
    // (2N + 1 points each), the vertical midpoints on the line y + 1/2 (N + 1 points).
    Line top, mid, bottom;
    map_line(map, latlong, float(row_begin) * inv_n, 2 * N + 1, 0.5f * inv_n, top);
    for (int y = row_begin; y < row_end; ++y) {
      map_line(map, latlong, (float(y) + 0.5f) * inv_n, N + 1, inv_n, mid);
      map_line(map, latlong, float(y + 1) * inv_n, 2 * N + 1, 0.5f * inv_n, bottom);
      for (int x = 0; x < N; ++x) {
        // Around the texel, in kOutline's order.
        const std::pair<const Line*, int> at[kOutline] = {{&top, 2 * x},        {&top, 2 * x + 1}, {&top, 2 * x + 2},
                                                          {&mid, x + 1},        {&bottom, 2 * x + 2},
                                                          {&bottom, 2 * x + 1}, {&bottom, 2 * x}, {&mid, x}};
        float umin = 2, umax = -2, vmin = 2, vmax = -2, us[kOutline], vs[kOutline];
        bool north = false, south = false;
        float zsum = 0;
        for (int k = 0; k < kOutline; ++k) {
          const Line& l = *at[k].first;
          const int i = at[k].second;
          us[k] = l.u[i];
          vs[k] = l.v[i];
          vmin = std::min(vmin, l.v[i]);
          vmax = std::max(vmax, l.v[i]);
          zsum += l.z[i];
          north = north || l.z[i] > pole_z;
          south = south || l.z[i] < -pole_z;
        }
        for (float u : us) umin = std::min(umin, u), umax = std::max(umax, u);
        float peak;
        const auto [sag_u, sag_v] = nearest ? envpis::detail::outline_sag(us, vs, w, h) : std::pair<float, float>{0, 0};
        if (latlong && !north && !south && winds_around_pole(us)) (zsum > 0 ? north : south) = true;
        if (latlong) {
          if (umax - umin > 0.5f) {  // the outline crosses the seam: unwrap
            umin = 2, umax = -2;
            for (float u : us) {
              const float uu = u < 0.5f ? u + 1.0f : u;
              umin = std::min(umin, uu), umax = std::max(umax, uu);
            }
          }
          if (north) vmin = 0;
          if (south) vmax = 1;
          int c0, c1, r0, r1;
          envpis::detail::footprint(umin * w - 0.5f, umax * w - 0.5f, nearest, sag_u, c0, c1);
          envpis::detail::footprint(vmin * h - 0.5f, vmax * h - 0.5f, nearest, sag_v, r0, r1);
          if (north || south) c0 = 0, c1 = w - 1;
          r0 = std::max(r0, 0);
          r1 = std::min(r1, h - 1);
          peak = 0;
          for (int r = r0; r <= r1; ++r) peak = std::max(peak, tree.query_wrapped(r, c0, c1));
        } else if (umax - umin > 0.5f || vmax - vmin > 0.5f) {
          peak = map_max;  // the outline crosses the map square's folded edge (rotated maps only)
        } else {
          int c0, c1, r0, r1;
          envpis::detail::footprint(umin * w - 0.5f, umax * w - 0.5f, nearest, sag_u, c0, c1);
          envpis::detail::footprint(vmin * h - 0.5f, vmax * h - 0.5f, nearest, sag_v, r0, r1);
          peak = 0;
          for (int r = r0; r <= r1; ++r)
            for (int c = c0; c <= c1; ++c) {  // past the square's edge, the texels eval's look-up reads
              int xi = c, yi = r;
              if (!equal_area_wrap(w, xi, yi)) {
                xi = std::clamp(xi, 0, w - 1);
                yi = std::clamp(yi, 0, h - 1);
              }
              peak = std::max(peak, lum[static_cast<std::size_t>(yi) * w + xi]);
            }
        }
        peaks[static_cast<std::size_t>(y) * N + x] = peak;
      }
      std::swap(top, bottom);
    }
  });
  return peaks;
}

}  // namespace envpis::test::old_peak
