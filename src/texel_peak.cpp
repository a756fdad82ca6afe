// SPDX-License-Identifier: Apache-2.0
#include "texel_peak.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "envpis/equal_area.h"
#include "parallel.h"

#define ENVPIS_KERNEL_NS scalar
#include "simd_ops.h"

namespace envpis::detail {

namespace {

using VF = scalar::simd::stdx::native_simd<float>;

// atan2_fast (simd_ops.h) on lanes: the same operations in the same order, so the same bits per lane.
VF atan2_lanes(VF y, VF x) {
  using namespace scalar::simd;
  const VF ax = vabs(x), ay = vabs(y);
  const VF hi = vmax(ax, ay), lo = vmin(ax, ay);
  VF a = select(hi > VF(0.0f), atan_unit(lo / hi), VF(0.0f));  // 0 / 0 in the lanes it drops: no trap
  a = select(ay > ax, VF(1.57079632679489661923f) - a, a);
  a = select(x < VF(0.0f), VF(3.14159265358979323846f) - a, a);
  return vcopysign(a, y);
}

// direction_to_latlong (environment_map.cpp) on lanes, likewise bit for bit.
void latlong_lanes(VF x, VF y, VF z, VF& u, VF& v) {
  using scalar::simd::select;
  VF phi = atan2_lanes(y, x);
  phi = select(phi < VF(0.0f), phi + VF(2 * kPi), phi);
  u = phi * VF(0.5f * kInvPi);
  u = select(u >= VF(1.0f), u - VF(1.0f), u);
  v = atan2_lanes(scalar::simd::vsqrt(x * x + y * y), z) * VF(kInvPi);
}

// Range maximum over the columns of each row. Nearly every footprint spans a few columns and is
// scanned directly in the map's row; a wide one (near a lat-long map's poles) reads maxima of aligned
// blocks of kBlock columns, and a whole row its precomputed maximum. The maximum of floats is exact in
// any order, so the result is the same as any other range-maximum structure's; this one adds w / kBlock
// floats per row instead of a max tree's 2w (64 MB for a 4096 x 2048 map), and reads contiguous memory.
class RowMax {
 public:
  RowMax(const std::vector<float>& lum, int w, int h)
      : lum_(lum.data()), w_(w), blocks_((w + kBlock - 1) / kBlock),
        block_(static_cast<std::size_t>(h) * blocks_), row_(h) {
    detail::parallel_for(0, h, [&](int begin, int end) {
      for (int y = begin; y < end; ++y) {
        const float* r = lum_ + static_cast<std::size_t>(y) * w_;
        float* b = &block_[static_cast<std::size_t>(y) * blocks_];
        for (int k = 0; k < blocks_; ++k) b[k] = scan(r, k * kBlock, std::min(w_, (k + 1) * kBlock) - 1);
        row_[y] = scan(b, 0, blocks_ - 1);
      }
    });
  }
  /// Max over columns [a, b] of row y, 0 <= a <= b < width.
  float query(int y, int a, int b) const {
    if (a == 0 && b == w_ - 1) return row_[y];
    const float* r = lum_ + static_cast<std::size_t>(y) * w_;
    if (b - a < 2 * kBlock) return scan(r, a, b);
    const int ka = (a + kBlock - 1) / kBlock, kb = (b + 1) / kBlock;  // whole blocks [ka, kb)
    float m = std::max(scan(r, a, ka * kBlock - 1), scan(r, kb * kBlock, b));
    return std::max(m, scan(&block_[static_cast<std::size_t>(y) * blocks_], ka, kb - 1));
  }
  /// Max over columns [a, b] taken modulo the width (a range that crosses the seam wraps around).
  float query_wrapped(int y, int a, int b) const {
    if (b - a + 1 >= w_) return row_[y];
    if (a >= 0 && b < w_) return query(y, a, b);  // nearly always: no integer division
    a = ((a % w_) + w_) % w_;
    b = ((b % w_) + w_) % w_;
    return a <= b ? query(y, a, b) : std::max(query(y, a, w_ - 1), query(y, 0, b));
  }

 private:
  static constexpr int kBlock = 32;
  // Max of p[a..b]; 0 for an empty range (every value is >= 0). Four running maxima, so that the
  // loads and comparisons overlap instead of waiting on one chain (the maximum is the same in any order).
  static float scan(const float* p, int a, int b) {
    float m0 = 0, m1 = 0, m2 = 0, m3 = 0;
    int i = a;
    for (; i + 3 <= b; i += 4) {
      m0 = std::max(m0, p[i]);
      m1 = std::max(m1, p[i + 1]);
      m2 = std::max(m2, p[i + 2]);
      m3 = std::max(m3, p[i + 3]);
    }
    for (; i <= b; ++i) m0 = std::max(m0, p[i]);
    return std::max(std::max(m0, m1), std::max(m2, m3));
  }
  const float* lum_;
  int w_, blocks_;
  std::vector<float> block_, row_;
};

// The outline of a texel: its corners and edge midpoints, going round.
constexpr int kOutline = 8;

// Whether the outline's azimuths (in turns, [0, 1)) wind once around a pole: the texel contains it.
// A step of nearly half a turn means the pole lies on the outline, between two of its points.
bool winds_around_pole(const float* us) {
  float turns = 0;
  for (int k = 0; k < kOutline; ++k) {
    float d = us[(k + 1) % kOutline] - us[k];
    // d - round(d) for d in (-1, 1), without the library call (round takes halves away from zero).
    d -= d >= 0.5f ? 1.0f : (d <= -0.5f ? -1.0f : 0.0f);
    if (std::fabs(d) > 0.4f) return true;
    turns += d;
  }
  return std::fabs(turns) > 0.5f;
}

// Map coordinates (u, v) and map-space directions (dx, dy, dz) of points along one horizontal line of
// the table, with the square's coordinates as scratch (kept between lines: no allocation per line).
struct Line {
  std::vector<float> u, v, su, sv, dx, dy, dz;
};

// `count` points (i * step, y) of the equal-area square, i = 0 .. count - 1, in the map's coordinates.
void map_line(const EnvironmentMap& map, float y, int count, float step, Line& out) {
  for (auto* a : {&out.u, &out.v, &out.su, &out.sv, &out.dx, &out.dy, &out.dz}) a->resize(count);
  for (int i = 0; i < count; ++i) out.su[i] = std::min(1.0f, float(i) * step), out.sv[i] = y;
  equal_area_square_to_sphere(static_cast<std::size_t>(count), out.su.data(), out.sv.data(), out.dx.data(),
                              out.dy.data(), out.dz.data());
  map_coordinates(map, static_cast<std::size_t>(count), out.dx.data(), out.dy.data(), out.dz.data(), out.u.data(),
                  out.v.data());
}

// What every texel's box needs to know about the map.
struct BoxSetup {
  int w, h;
  bool latlong, nearest;
  float pole_z;  // an outline point this close to a lat-long pole has no usable azimuth
};

// Where a texel's peak is read: map rows [r0, r1] x columns [c0, c1] (lat-long: the columns modulo the
// width; equal-area: wrapped as eval reads them), or, when `known` >= 0, that value.
struct Box {
  int r0 = 0, r1 = -1, c0 = 0, c1 = -1;
  float known = -1;
};

// The box of texel x of the row between lines `top` and `bottom` (its outline, in kOutline's order).
Box texel_box(const BoxSetup& m, const Line& top, const Line& mid, const Line& bottom, int x, float map_max) {
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
    zsum += l.dz[i];
    north = north || l.dz[i] > m.pole_z;
    south = south || l.dz[i] < -m.pole_z;
  }
  for (float u : us) umin = std::min(umin, u), umax = std::max(umax, u);
  const auto [sag_u, sag_v] = m.nearest ? outline_sag(us, vs, m.w, m.h) : std::pair<float, float>{0, 0};
  Box b;
  if (!m.latlong && (umax - umin > 0.5f || vmax - vmin > 0.5f)) {
    b.known = map_max;  // the outline crosses the map square's folded edge (rotated maps only)
    return b;
  }
  if (m.latlong && !north && !south && winds_around_pole(us)) (zsum > 0 ? north : south) = true;
  if (m.latlong && umax - umin > 0.5f) {  // the outline crosses the seam: unwrap
    umin = 2, umax = -2;
    for (float u : us) {
      const float uu = u < 0.5f ? u + 1.0f : u;
      umin = std::min(umin, uu), umax = std::max(umax, uu);
    }
  }
  if (m.latlong && north) vmin = 0;
  if (m.latlong && south) vmax = 1;
  footprint(umin * m.w - 0.5f, umax * m.w - 0.5f, m.nearest, sag_u, b.c0, b.c1);
  footprint(vmin * m.h - 0.5f, vmax * m.h - 0.5f, m.nearest, sag_v, b.r0, b.r1);
  if (m.latlong) {
    if (north || south) b.c0 = 0, b.c1 = m.w - 1;
    b.r0 = std::max(b.r0, 0);
    b.r1 = std::min(b.r1, m.h - 1);
  }
  return b;
}

// The largest texel of box b.
float box_peak(const BoxSetup& m, const Box& b, const RowMax& rows, const std::vector<float>& lum) {
  if (b.known >= 0) return b.known;
  float peak = 0;
  if (m.latlong) {
    for (int r = b.r0; r <= b.r1; ++r) peak = std::max(peak, rows.query_wrapped(r, b.c0, b.c1));
    return peak;
  }
  for (int r = b.r0; r <= b.r1; ++r)
    for (int c = b.c0; c <= b.c1; ++c) {  // past the square's edge, the texels eval's look-up reads
      int xi = c, yi = r;
      if (!equal_area_wrap(m.w, xi, yi)) {
        xi = std::clamp(xi, 0, m.w - 1);
        yi = std::clamp(yi, 0, m.h - 1);
      }
      peak = std::max(peak, lum[static_cast<std::size_t>(yi) * m.w + xi]);
    }
  return peak;
}

// Asks for the cache lines a narrow lat-long box starts in, some texels before box_peak reads them:
// successive texels of a table row walk across the map's rows, so their first reads missed the cache.
void prefetch_box(const BoxSetup& m, const Box& b, const float* lum) {
  if (!m.latlong || b.known >= 0 || b.r1 - b.r0 > 8 || b.c1 - b.c0 > 32) return;
  const int c = std::clamp(b.c0, 0, m.w - 1);
  for (int r = b.r0; r <= b.r1; ++r) __builtin_prefetch(lum + static_cast<std::size_t>(r) * m.w + c);
}

// Calls visit(x, y, peak) once for every texel of the N x N grid, rows in parallel (each row from one
// thread; rows in any order). Each row's boxes are found first, then read with the boxes kAhead texels
// on prefetched.
template <class Visit>
void for_each_peak(const EnvironmentMap& map, const std::vector<float>& lum, int N, const Visit& visit) {
  const int w = map.width(), h = map.height();
  const BoxSetup m{w, h, map.layout() != MapLayout::EqualArea, map.filter() == MapFilter::Nearest,
                   std::cos(1e-3f * std::sqrt(4.0f * kPi) / float(N))};
  const RowMax rows(lum, w, h);
  const float map_max = *std::max_element(lum.begin(), lum.end());
  const float inv_n = 1.0f / float(N);
  constexpr int kAhead = 8;

  detail::parallel_for(0, N, [&](int row_begin, int row_end) {
    // Outline points are shared: the corners and horizontal midpoints lie on the lines y and y + 1
    // (2N + 1 points each), the vertical midpoints on the line y + 1/2 (N + 1 points).
    Line top, mid, bottom;
    std::vector<Box> boxes(N);
    map_line(map, float(row_begin) * inv_n, 2 * N + 1, 0.5f * inv_n, top);
    for (int y = row_begin; y < row_end; ++y) {
      map_line(map, (float(y) + 0.5f) * inv_n, N + 1, inv_n, mid);
      map_line(map, float(y + 1) * inv_n, 2 * N + 1, 0.5f * inv_n, bottom);
      for (int x = 0; x < N; ++x) boxes[x] = texel_box(m, top, mid, bottom, x, map_max);
      for (int x = 0; x < std::min(N, kAhead); ++x) prefetch_box(m, boxes[x], lum.data());
      for (int x = 0; x < N; ++x) {
        if (x + kAhead < N) prefetch_box(m, boxes[x + kAhead], lum.data());
        visit(x, y, box_peak(m, boxes[x], rows, lum));
      }
      std::swap(top, bottom);
    }
  });
}

}  // namespace

void footprint(float a, float b, bool nearest, float sag, int& lo, int& hi) {
  if (nearest) {
    const float margin = 0.01f + 0.5f * sag;
    lo = static_cast<int>(std::floor(a - margin + 0.5f));
    hi = static_cast<int>(std::floor(b + margin + 0.5f));
  } else {
    const float margin = 0.05f + 0.25f * (b - a);
    lo = static_cast<int>(std::floor(a - margin));
    hi = static_cast<int>(std::floor(b + margin)) + 1;
  }
}

std::pair<float, float> outline_sag(const float* us, const float* vs, int w, int h) {
  float su = 0, sv = 0;
  for (int e = 0; e < 4; ++e) {
    const int c0 = 2 * e, m = 2 * e + 1, c1 = (2 * e + 2) % 8;
    float d0 = us[c0] - us[m], d1 = us[c1] - us[m];
    d0 -= std::round(d0), d1 -= std::round(d1);
    su = std::max(su, std::fabs(0.5f * (d0 + d1)) * float(w));
    sv = std::max(sv, std::fabs(0.5f * (vs[c0] + vs[c1]) - vs[m]) * float(h));
  }
  return {su, sv};
}


void map_coordinates(const EnvironmentMap& map, std::size_t n, float* x, float* y, float* z, float* u, float* v) {
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 md = map.to_map({x[i], y[i], z[i]});
    x[i] = md.x, y[i] = md.y, z[i] = md.z;
  }
  std::size_t i = 0;
  if (map.layout() != MapLayout::EqualArea) {
    constexpr std::size_t L = VF::size();
    for (; i + L <= n; i += L) {
      VF pu, pv;
      latlong_lanes(VF(x + i, scalar::simd::stdx::element_aligned), VF(y + i, scalar::simd::stdx::element_aligned),
                    VF(z + i, scalar::simd::stdx::element_aligned), pu, pv);
      pu.copy_to(u + i, scalar::simd::stdx::element_aligned);
      pv.copy_to(v + i, scalar::simd::stdx::element_aligned);
    }
  }
  for (; i < n; ++i) {
    const Vec3 md{x[i], y[i], z[i]};
    const Point2 p = map.layout() != MapLayout::EqualArea ? direction_to_latlong(md) : equal_area_sphere_to_square(md);
    u[i] = p.x, v[i] = p.y;
  }
}

std::vector<float> texel_peaks(const EnvironmentMap& map, const std::vector<float>& lum, int N) {
  std::vector<float> peaks(static_cast<std::size_t>(N) * N, 0.0f);
  for_each_peak(map, lum, N, [&](int x, int y, float peak) { peaks[static_cast<std::size_t>(y) * N + x] = peak; });
  return peaks;
}

void raise_to_peaks(const EnvironmentMap& map, const std::vector<float>& lum, float inv_k, FineLevel& fine) {
  std::vector<float>& func = fine.values();
  for_each_peak(map, lum, fine.resolution(), [&](int x, int y, float peak) {
    float& v = func[fine.index(x, y)];
    v = std::max(v, peak * inv_k);
  });
}

}  // namespace envpis::detail
