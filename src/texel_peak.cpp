#include "texel_peak.h"



#include <algorithm>
#include <cmath>
#include <utility>

#include "envpis/equal_area.h"
#include "parallel.h"

namespace envpis::detail {

namespace {

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

// Texel range [lo, hi] that eval can read at pixel coordinates [a, b] (texel centres at integers): a
// bilinear look-up reads the texels either side, a nearest one the closest. The margin covers the
// outline's curvature between its sample points. Bilinear: a fixed fraction of the extent. Nearest:
// `sag`, how far the outline's edge midpoints lie off the chords of their corners (pixels), measured
// per texel. Between two sample points half an edge apart the curve strays a quarter of that (a
// sagitta scales with the square of the chord); half of it plus 0.01 pixel of round-off is kept. A
// fixed 0.05 + 0.25 (b - a) let every nearest texel reach its neighbours: around a sun of 53 texels,
// equal-area texels aligned with an equal-area map's then drew 77% of the light samples onto black
// (docs/cycles.md, "Why Cycles converged faster in the highlight").
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

// The outline's largest sagitta along u and along v, in pixels: for each of the 4 edges (corners at
// even k, the midpoint between them at odd k), the midpoint's distance from the corners' mean. Azimuth
// differences are taken across the seam.
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

}  // namespace

std::vector<float> texel_peaks(const EnvironmentMap& map, const std::vector<float>& lum, int N) {
  const int w = map.width(), h = map.height();
  const bool latlong = map.layout() != MapLayout::EqualArea;
  const bool nearest = map.filter() == MapFilter::Nearest;
  const RowMaxTree tree(lum, w, h);
  const float map_max = *std::max_element(lum.begin(), lum.end());
  // An outline point this close to a lat-long pole (a thousandth of a texel side) has no usable azimuth.
  const float pole_z = std::cos(1e-3f * std::sqrt(4.0f * kPi) / float(N));
  std::vector<float> peaks(static_cast<std::size_t>(N) * N, 0.0f);
  const float inv_n = 1.0f / float(N);

  detail::parallel_for(0, N, [&](int row_begin, int row_end) {
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
        const auto [sag_u, sag_v] = nearest ? outline_sag(us, vs, w, h) : std::pair<float, float>{0, 0};
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
          footprint(umin * w - 0.5f, umax * w - 0.5f, nearest, sag_u, c0, c1);
          footprint(vmin * h - 0.5f, vmax * h - 0.5f, nearest, sag_v, r0, r1);
          if (north || south) c0 = 0, c1 = w - 1;
          r0 = std::max(r0, 0);
          r1 = std::min(r1, h - 1);
          peak = 0;
          for (int r = r0; r <= r1; ++r) peak = std::max(peak, tree.query_wrapped(r, c0, c1));
        } else if (umax - umin > 0.5f || vmax - vmin > 0.5f) {
          peak = map_max;  // the outline crosses the map square's folded edge (rotated maps only)
        } else {
          int c0, c1, r0, r1;
          footprint(umin * w - 0.5f, umax * w - 0.5f, nearest, sag_u, c0, c1);
          footprint(vmin * h - 0.5f, vmax * h - 0.5f, nearest, sag_v, r0, r1);
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

}  // namespace envpis::detail
