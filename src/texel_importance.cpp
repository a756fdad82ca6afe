// SPDX-License-Identifier: Apache-2.0
#include "texel_importance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "envpis/equal_area.h"
#include "envpis_assert.h"
#include "huge_pages.h"
#include "parallel.h"
#include "texel_filter.h"
#include "texel_peak.h"

namespace envpis::detail {

namespace {

// What every step needs to know about the map and the table.
struct Setup {
  const EnvironmentMap& map;
  const FineLevel& fine;
  int w, h, N;
  bool latlong;
  std::size_t total;      // N^2 table texels
  double table_texel_sr;  // solid angle of a table texel
  double ea_src_sr;       // solid angle of an equal-area map texel
  std::vector<float> lum;  // the map texels' channel averages

  Setup(const EnvironmentMap& m, const FineLevel& f)
      : map(m), fine(f), w(m.width()), h(m.height()), N(f.resolution()), latlong(m.layout() != MapLayout::EqualArea),
        total(static_cast<std::size_t>(N) * N), table_texel_sr(4.0 * kPi / double(total)),
        ea_src_sr(4.0 * kPi / (double(w) * h)) {
    assign_fresh(lum, static_cast<std::size_t>(w) * h, 0.0f);
    parallel_for(0, h, [&](int begin, int end) {
      for (int y = begin; y < end; ++y)
        for (int x = 0; x < w; ++x) {
          const Rgb L = map.texel(x, y);
          lum[static_cast<std::size_t>(y) * w + x] = static_cast<float>((double(L.r) + L.g + L.b) / 3.0);
        }
    });
  }
  float lum_at(int x, int y) const { return lum[static_cast<std::size_t>(y) * w + x]; }
  // Bilinear look-up of the channel average at map coordinates (u, v) (map_coordinates: the same
  // mapping as EnvironmentMap::eval).
  float lookup(float u, float v) const {
    const auto at = [this](int x, int y) { return lum_at(x, y); };
    return latlong ? bilinear_latlong(at, w, h, u, v) : bilinear_equal_area(at, w, u, v);
  }
};

// The gather's s x s look-ups per table texel: about one per map texel.
int gather_strata(const Setup& su) {
  const double ratio = double(su.w) * su.h / double(su.total);
  return std::clamp(static_cast<int>(std::ceil(std::sqrt(ratio) - 0.25)), 1, 8);
}

// 3. Combine: splat where map texels are small, gather elsewhere; either one where the other is 0
// (so a texel that sees light by either route keeps a positive density).
float combine(double splatted, double texel_sr, float gathered, bool small) {
  const double sp = splatted / texel_sr, ga = gathered;
  const double v = small ? (sp > 0 ? sp : ga) : (ga > 0 ? ga : sp);
  return static_cast<float>(std::min<double>(v, std::numeric_limits<float>::max()));
}

// 1. Gather: the average of s x s stratified bilinear look-ups over each table texel. Accurate where
// map texels are at least about as large as table texels. Also marks the texels where map texels are
// smaller than half a table texel (`small`), and combines each finished row with the splat (step 3)
// straight into `func`: the gathered values and marks live in one row's buffers, not in N^2 arrays.
void gather_combine(const Setup& su, const double* splatted, std::vector<float>& func) {
  const int N = su.N;
  // A lat-long texel at polar angle theta is smaller than half a table texel when sin(theta) is below
  // this (its solid angle is about (2 pi / w)(pi / h) sin theta).
  const float small_sin =
      su.latlong ? static_cast<float>(0.5 * su.table_texel_sr / ((2.0 * kPi / su.w) * (kPi / su.h))) : 0.0f;
  const bool all_small = !su.latlong && su.ea_src_sr < 0.5 * su.table_texel_sr;
  const int s = gather_strata(su);
  const float inv = 1.0f / float(N * s);
  parallel_for(0, N, [&](int row_begin, int row_end) {
    const std::size_t m = static_cast<std::size_t>(N) * s;
    std::vector<float> pu(m), pv(m), dx(m), dy(m), dz(m), mu(m), mv(m), gathered(N);
    std::vector<std::uint8_t> small(N);
    for (std::size_t i = 0; i < m; ++i) pu[i] = (float(i) + 0.5f) * inv;
    for (int y = row_begin; y < row_end; ++y) {
      std::fill(gathered.begin(), gathered.end(), 0.0f);  // summed in float, stratum row by row
      for (int sy = 0; sy < s; ++sy) {
        std::fill(pv.begin(), pv.end(), (float(y * s + sy) + 0.5f) * inv);
        equal_area_square_to_sphere(m, pu.data(), pv.data(), dx.data(), dy.data(), dz.data());
        map_coordinates(su.map, m, dx.data(), dy.data(), dz.data(), mu.data(), mv.data());  // dz: map space
        for (int x = 0; x < N; ++x) {
          double acc = 0;
          for (int sx = 0; sx < s; ++sx) {
            const std::size_t i = static_cast<std::size_t>(x) * s + sx;
            acc += su.lookup(mu[i], mv[i]);
          }
          gathered[x] += static_cast<float>(acc / (double(s) * s));
          if (sy == s / 2) {
            const float mz = dz[static_cast<std::size_t>(x) * s + s / 2];
            small[x] = all_small || 1.0f - mz * mz < small_sin * small_sin;
          }
        }
      }
      for (int x = 0; x < N; ++x) {
        const std::size_t i = su.fine.index(x, y);
        func[i] = combine(splatted[i], su.table_texel_sr, gathered[x], small[x]);
      }
    }
  });
}

// Sub-texel splits of map row y for the splat: only where the splat is used (map texels smaller than
// half a table texel); elsewhere one point per map texel is enough for its role as a fallback.
void splat_splits(const Setup& su, int y, int& kx, int& ky) {
  const double table_side = std::sqrt(su.table_texel_sr);
  const double theta = kPi * (y + 0.5) / su.h;
  const double height = su.latlong ? kPi / su.h : std::sqrt(su.ea_src_sr);
  const double width = su.latlong ? 2.0 * kPi / su.w * std::max(std::sin(theta), std::sin(0.5 * kPi / su.h))
                                  : std::sqrt(su.ea_src_sr);
  kx = ky = 1;
  if (width * height >= su.table_texel_sr) return;  // 2x margin over the small-texel threshold
  kx = std::clamp(static_cast<int>(std::ceil(2.0 * width / table_side)), 1, 16);
  ky = std::clamp(static_cast<int>(std::ceil(2.0 * height / table_side)), 1, 16);
}

// One map row's splat points: equal-area coordinates (u, v) and energy e (importance x solid angle).
struct SplatRow {
  std::vector<float> u, v, e;
};

// Azimuth cosines and sines of the sub-texel columns (x + (i + 0.5) / kx) / w of a lat-long map split
// kx ways, entry x * kx + i: latlong_to_direction's own values (its point at theta = pi / 2, where
// sin theta is exactly 1), so a point s * cos, s * sin, c is the one it returns, bit for bit, with
// the row's sin and cos computed once instead of per point.
struct SplitColumns {
  std::vector<float> cos_phi, sin_phi;
};

SplitColumns split_columns(int w, int kx) {
  SplitColumns c;
  c.cos_phi.resize(static_cast<std::size_t>(w) * kx);
  c.sin_phi.resize(c.cos_phi.size());
  parallel_for(0, w, [&](int begin, int end) {
    for (int x = begin; x < end; ++x)
      for (int i = 0; i < kx; ++i) {
        const Vec3 d = latlong_to_direction({float((x + (i + 0.5) / kx) / w), 0.5f});
        c.cos_phi[static_cast<std::size_t>(x) * kx + i] = d.x;
        c.sin_phi[static_cast<std::size_t>(x) * kx + i] = d.y;
      }
  });
  return c;
}

void splat_row(const Setup& su, int y, const std::vector<float>& col_cos, const std::vector<float>& col_sin,
               const std::vector<SplitColumns>& split, SplatRow& out, std::vector<float>& mx,
               std::vector<float>& my, std::vector<float>& mz) {
  int kx, ky;
  splat_splits(su, y, kx, ky);
  const int w = su.w, h = su.h;
  const std::size_t m = static_cast<std::size_t>(w) * kx * ky;
  for (auto* a : {&mx, &my, &mz, &out.u, &out.v, &out.e}) a->resize(m);
  std::size_t k = 0;
  for (int j = 0; j < ky; ++j) {
    const double v0 = (y + double(j) / ky) / h, v1 = (y + double(j + 1) / ky) / h;
    const double sub_sr = su.latlong ? 2.0 * kPi / (double(w) * kx) * (std::cos(kPi * v0) - std::cos(kPi * v1))
                                     : su.ea_src_sr / (double(kx) * ky);
    const float st = static_cast<float>(std::sin(kPi * 0.5 * (v0 + v1)));
    const float ct = static_cast<float>(std::cos(kPi * 0.5 * (v0 + v1)));
    const Vec3 row = su.latlong ? latlong_to_direction({0.0f, float(0.5 * (v0 + v1))}) : Vec3{};  // {sin, 0, cos}
    for (int x = 0; x < w; ++x) {
      const float e = static_cast<float>(double(su.lum_at(x, y)) * sub_sr);
      for (int i = 0; i < kx; ++i, ++k) {
        Vec3 md;
        if (su.latlong && kx == 1) {
          md = {st * col_cos[x], st * col_sin[x], ct};
        } else if (su.latlong) {  // latlong_to_direction(uv) of the point below
          const std::size_t c = static_cast<std::size_t>(x) * kx + i;
          md = {row.x * split[kx].cos_phi[c], row.x * split[kx].sin_phi[c], row.z};
        } else {
          const Point2 uv{float((x + (i + 0.5) / kx) / w), float(0.5 * (v0 + v1))};
          md = su.latlong ? latlong_to_direction(uv) : equal_area_square_to_sphere(uv);
        }
        const Vec3 d = su.map.to_world(md);
        mx[k] = d.x;
        my[k] = d.y;
        mz[k] = d.z;
        out.e[k] = e;
      }
    }
  }
  equal_area_sphere_to_square(m, mx.data(), my.data(), mz.data(), out.u.data(), out.v.data());
}

// Spreads a row's points with bilinear (tent) weights over the 2 x 2 table texels around each, adding
// only to table rows [b0, b1): threads that own disjoint bands of rows add every point's share in the
// same order as one thread would, so each texel's double sum is the same, bit for bit.
void splat_accumulate(const Setup& su, const SplatRow& r, int b0, int b1, double* out) {
  const int N = su.N;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    if (!(r.e[k] > 0)) continue;
    const float px = r.u[k] * N - 0.5f, py = r.v[k] * N - 0.5f;
    const float fx = std::floor(px), fy = std::floor(py);
    const float tx = px - fx, ty = py - fy;
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    const double e = r.e[k];
    if (x0 >= 0 && y0 >= 0 && x0 + 1 < N && y0 + 1 < N) {  // interior: no wrapping
      if (y0 >= b0 && y0 < b1) {
        out[su.fine.index(x0, y0)] += e * ((1 - tx) * (1 - ty));
        out[su.fine.index(x0 + 1, y0)] += e * (tx * (1 - ty));
      }
      if (y0 + 1 >= b0 && y0 + 1 < b1) {
        out[su.fine.index(x0, y0 + 1)] += e * ((1 - tx) * ty);
        out[su.fine.index(x0 + 1, y0 + 1)] += e * (tx * ty);
      }
      continue;
    }
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        int xi = x0 + i, yi = y0 + j;
        if (!equal_area_wrap(N, xi, yi) || yi < b0 || yi >= b1) continue;
        out[su.fine.index(xi, yi)] += e * ((i ? tx : 1 - tx) * (j ? ty : 1 - ty));
      }
  }
}

// 2. Splat: every map texel's importance times its solid angle is spread over the table texels around
// its centre. Energy-conserving where map texels are smaller than table texels (near a lat-long map's
// poles), where point look-ups would miss a small bright texel or over-count it. A map texel taller or
// wider than half a table texel is split into sub-texels first (each with its exact solid angle), so
// the splat stays smooth. Rows are processed in chunks: parallel mapping, then the accumulation in
// parallel over bands of table rows (each thread reads every point and keeps its band's shares).
std::unique_ptr<double[]> splat(const Setup& su) {
  std::unique_ptr<double[]> out(new double[su.total]);  // uninitialised: zeroed by every thread
  advise_huge_pages(out.get(), su.total * sizeof(double));
  parallel_fill(out.get(), su.total, 0.0);
  // Azimuth sines and cosines of the map's column centres (lat-long, one split per column).
  std::vector<float> col_cos(su.w), col_sin(su.w);
  for (int x = 0; x < su.w; ++x) {
    const double phi = 2.0 * kPi * (x + 0.5) / su.w;
    col_cos[x] = static_cast<float>(std::cos(phi));
    col_sin[x] = static_cast<float>(std::sin(phi));
  }
  // The split columns of every kx that a row uses (lat-long only).
  std::vector<SplitColumns> split(17);
  for (int y = 0; y < su.h && su.latlong; ++y) {
    int kx, ky;
    splat_splits(su, y, kx, ky);
    if (kx > 1 && split[kx].cos_phi.empty()) split[kx] = split_columns(su.w, kx);
  }
  const int chunk = std::max(1, std::min(su.h, (1 << 18) / su.w));
  const int bands = std::min(su.N, parallel_threads());
  std::vector<SplatRow> rows(chunk);
  for (int y0 = 0; y0 < su.h; y0 += chunk) {
    const int y1 = std::min(su.h, y0 + chunk);
    parallel_for(y0, y1, [&](int row_begin, int row_end) {
      std::vector<float> mx, my, mz;
      for (int y = row_begin; y < row_end; ++y) splat_row(su, y, col_cos, col_sin, split, rows[y - y0], mx, my, mz);
    });
    parallel_for(0, bands, [&](int band_begin, int band_end) {
      const int b0 = int(std::int64_t(su.N) * band_begin / bands), b1 = int(std::int64_t(su.N) * band_end / bands);
      for (int y = y0; y < y1; ++y) splat_accumulate(su, rows[y - y0], b0, b1, out.get());
    });
  }
  return out;
}

// Whether every texel has the same channel average (to within 1e-6); rows in parallel (the minimum and
// maximum are the same in any order).
bool map_is_constant(const EnvironmentMap& map) {
  std::vector<float> lo(map.height()), hi(map.height());
  parallel_for(0, map.height(), [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      lo[y] = std::numeric_limits<float>::max(), hi[y] = 0;
      for (int x = 0; x < map.width(); ++x) {
        const float a = map.texel(x, y).average();
        lo[y] = std::min(lo[y], a);
        hi[y] = std::max(hi[y], a);
      }
    }
  });
  const float l = *std::min_element(lo.begin(), lo.end()), h = *std::max_element(hi.begin(), hi.end());
  return h - l <= 1e-6f * h;
}

// v = op(v) for every value, in parallel.
template <class Op>
void transform_all(std::vector<float>& func, const Op& op) {
  constexpr std::size_t kBlock = std::size_t(1) << 16;
  const int blocks = static_cast<int>((func.size() + kBlock - 1) / kBlock);
  parallel_for(0, blocks, [&](int begin, int end) {
    const std::size_t e = std::min(func.size(), std::size_t(end) * kBlock);
    for (std::size_t i = std::size_t(begin) * kBlock; i < e; ++i) func[i] = op(func[i]);
  });
}

// The sum in index order, in double: one thread, so that it is the same number whatever the threads.
double ordered_sum(const std::vector<float>& func) {
  double sum = 0;
  for (float v : func) sum += v;
  return sum;
}

// The floor (positive density everywhere) or the MIS compensation; returns the integral. The values
// change in parallel; the sums stay ordered (ordered_sum).
double floor_or_compensate(std::vector<float>& func, double sum, double texel_sr, float floor, bool compensated) {
  const double n = double(func.size());
  if (compensated) {
    const float mean = static_cast<float>(sum / n);
    double csum = 0;
    for (float v : func) csum += std::max(0.0f, v - mean);
    if (csum > 0) {
      transform_all(func, [mean](float v) { return std::max(0.0f, v - mean); });
      return csum * texel_sr;
    }
  }
  const float min_value = static_cast<float>(floor * sum / n);
  if (min_value > 0) {
    transform_all(func, [min_value](float v) { return std::max(v, min_value); });
    sum = ordered_sum(func);
  }
  return sum * texel_sr;
}

}  // namespace

void gather_texel_importance(const EnvironmentMap& map, FineLevel& fine, float peak_ratio) {
  const Setup su(map, fine);
  std::vector<float>& func = fine.values();
  ENVPIS_ASSERT(func.size() == su.total);
  // Every texel is written (FineLevel sized and zeroed the array): no second fill. The splat first,
  // so that the gather combines each row as it finishes it; its N^2 doubles are freed right after.
  gather_combine(su, splat(su).get(), func);
  // 4. Peak bound: at least 1/K of the largest radiance eval returns inside the texel (texel_peak.h).
  if (peak_ratio > 0) raise_to_peaks(map, su.lum, 1.0f / peak_ratio, fine);
}

double finish_texel_importance(const EnvironmentMap& map, FineLevel& fine, const TexelImportanceOptions& options) {
  std::vector<float>& func = fine.values();
  const double sum = ordered_sum(func);
  if (!(sum > 0) || !std::isfinite(sum)) {
    std::fill(func.begin(), func.end(), 0.0f);
    return 0;
  }
  // A constant map's compensated table is the plain one.
  const bool compensated = options.compensated && !map_is_constant(map);
  return floor_or_compensate(func, sum, 4.0 * kPi / double(func.size()), options.floor, compensated);
}

double build_texel_importance(const EnvironmentMap& map, FineLevel& fine, const TexelImportanceOptions& options) {
  gather_texel_importance(map, fine, options.peak_ratio);
  return finish_texel_importance(map, fine, options);
}

}  // namespace envpis::detail
