#include "envpis/importance_table.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "distribution_util.h"
#include "envpis/equal_area.h"
#include "texel_peak.h"

#define ENVPIS_KERNEL_NS scalar
#include "kernels_impl.inl"

namespace envpis {

namespace {
constexpr int kMaxTop = 256;
constexpr int kMaxFine = 16384;
constexpr int kAutoFineCap = 2904;  // the automatic N of a 4096 x 2048 map: 67 MB of table
}  // namespace

void validate(const ImportanceTableOptions& options) {
  if (options.top_resolution < 1 || options.top_resolution > kMaxTop)
    throw Error("top-level resolution must be in 1.." + std::to_string(kMaxTop) + ", got " +
                std::to_string(options.top_resolution));
  if (options.fine_resolution < 0 || options.fine_resolution > kMaxFine)
    throw Error("fine resolution must be 0 (automatic) or in 1.." + std::to_string(kMaxFine));
  if (!(options.floor >= 0.0f && options.floor < 1.0f))
    throw Error("importance floor must be in [0, 1)");
  if (!(options.peak_ratio == 0.0f || (options.peak_ratio >= 1.0f && options.peak_ratio <= 1e6f)))
    throw Error("peak ratio must be 0 (off) or in [1, 1e6]");
}

ImportanceTable::ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(options);
  T_ = options.top_resolution;
  int n = options.fine_resolution;
  if (n == 0) {  // twice the map's resolution per side, up to kAutoFineCap (see the header)
    const double texels = double(map.width()) * double(map.height());
    const int n1 = static_cast<int>(std::ceil(std::sqrt(texels) - 1e-9));
    n = std::max(n1, std::min(2 * n1, kAutoFineCap));
  }
  F_ = std::max(1, (n + T_ - 1) / T_);
  N_ = T_ * F_;
  if (N_ > kMaxFine) {
    F_ = kMaxFine / T_;
    N_ = T_ * F_;
  }
  build_importance(map, options.floor, options.peak_ratio, options.compensated);
  build_cells();
  build_cones();
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::size_t ImportanceTable::texel_index(int x, int y) const {
  const int cx = x / F_, cy = y / F_, lx = x - cx * F_, ly = y - cy * F_;
  return ((static_cast<std::size_t>(cy) * T_ + cx) * F_ + ly) * F_ + lx;
}

float ImportanceTable::importance(int x, int y) const { return func_[texel_index(x, y)]; }

void ImportanceTable::build_importance(const EnvironmentMap& map, float floor, float peak_ratio, bool compensated) {
  const std::size_t total = static_cast<std::size_t>(N_) * N_;
  // The cell-major texel index is separable: index(x, y) = row_base[y] + col_base[x].
  std::vector<std::uint32_t> row_base(N_), col_base(N_);
  for (int i = 0; i < N_; ++i) {
    const std::size_t c = i / F_, l = i - c * F_;
    row_base[i] = static_cast<std::uint32_t>(c * T_ * F_ * F_ + l * F_);
    col_base[i] = static_cast<std::uint32_t>(c * F_ * F_ + l);
  }
  auto index = [&](int x, int y) { return std::size_t(row_base[y]) + col_base[x]; };
  const double table_texel_sr = 4.0 * kPi / double(total);
  const int w = map.width(), h = map.height();
  const bool latlong = map.layout() != MapLayout::EqualArea;
  // Solid angle of the map texel at map-space direction d.
  const double ea_src_sr = 4.0 * kPi / (double(w) * h);
  // A lat-long texel at polar angle theta is smaller than half a table texel when sin(theta) is below
  // this (its solid angle is about (2 pi / w)(pi / h) sin theta).
  const float small_sin = latlong ? static_cast<float>(0.5 * table_texel_sr / ((2.0 * kPi / w) * (kPi / h))) : 0.0f;
  const bool all_small = !latlong && ea_src_sr < 0.5 * table_texel_sr;

  // Importance (channel average) of the map's texels, and a bilinear look-up of it for a world
  // direction that matches EnvironmentMap::eval (same conventions) with fast polynomial atan2.
  std::vector<float> lum(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb L = map.texel(x, y);
      lum[static_cast<std::size_t>(y) * w + x] = static_cast<float>((double(L.r) + L.g + L.b) / 3.0);
    }
  auto lum_at = [&](int x, int y) { return lum[static_cast<std::size_t>(y) * w + x]; };
  auto lookup = [&](Vec3 world) -> float {
    const Vec3 md = map.to_map(world);
    if (!latlong) {
      const Point2 p = equal_area_sphere_to_square(md);
      const float px = p.x * w - 0.5f, py = p.y * h - 0.5f;
      const float fx = std::floor(px), fy = std::floor(py), tx = px - fx, ty = py - fy;
      float acc = 0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          int xi = static_cast<int>(fx) + i, yi = static_cast<int>(fy) + j;
          if (!equal_area_wrap(w, xi, yi)) {
            xi = std::clamp(xi, 0, w - 1);
            yi = std::clamp(yi, 0, h - 1);
          }
          acc += lum_at(xi, yi) * ((i ? tx : 1 - tx) * (j ? ty : 1 - ty));
        }
      return acc;
    }
    float phi = detail::scalar::atan2_fast(md.y, md.x);
    if (phi < 0) phi += 2 * kPi;
    const float theta = detail::scalar::atan2_fast(std::sqrt(md.x * md.x + md.y * md.y), md.z);
    const float px = phi * (0.5f * kInvPi) * w - 0.5f, py = theta * kInvPi * h - 0.5f;
    const float fx = std::floor(px), fy = std::floor(py), tx = px - fx, ty = py - fy;
    int x0 = static_cast<int>(fx), x1 = x0 + 1;
    if (x0 < 0) x0 += w;
    if (x1 >= w) x1 -= w;
    x0 = std::clamp(x0, 0, w - 1);
    x1 = std::clamp(x1, 0, w - 1);
    const int y0 = std::clamp(static_cast<int>(fy), 0, h - 1), y1 = std::clamp(static_cast<int>(fy) + 1, 0, h - 1);
    return (lum_at(x0, y0) * (1 - tx) + lum_at(x1, y0) * tx) * (1 - ty) +
           (lum_at(x0, y1) * (1 - tx) + lum_at(x1, y1) * tx) * ty;
  };

  // 1. Gather: the average of s x s stratified bilinear look-ups over each table texel. Accurate where
  // map texels are at least about as large as table texels.
  const double ratio = double(w) * h / double(total);
  const int s = std::clamp(static_cast<int>(std::ceil(std::sqrt(ratio) - 0.25)), 1, 8);
  std::vector<float> gather(total, 0.0f);
  std::vector<std::uint8_t> small_source(total, 0);  // map texels < half a table texel here
  const float inv = 1.0f / float(N_ * s);
  tbb::parallel_for(tbb::blocked_range<int>(0, N_), [&](const tbb::blocked_range<int>& rows) {
    const std::size_t m = static_cast<std::size_t>(N_) * s;
    std::vector<float> pu(m), pv(m), dx(m), dy(m), dz(m);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int sy = 0; sy < s; ++sy) {
        const float v = (float(y * s + sy) + 0.5f) * inv;
        for (std::size_t i = 0; i < m; ++i) {
          pu[i] = (float(i) + 0.5f) * inv;
          pv[i] = v;
        }
        equal_area_square_to_sphere(m, pu.data(), pv.data(), dx.data(), dy.data(), dz.data());
        for (int x = 0; x < N_; ++x) {
          double acc = 0;
          for (int sx = 0; sx < s; ++sx) {
            const std::size_t i = static_cast<std::size_t>(x) * s + sx;
            acc += lookup({dx[i], dy[i], dz[i]});
          }
          gather[index(x, y)] += static_cast<float>(acc / (double(s) * s));
          if (sy == s / 2) {
            const std::size_t i = static_cast<std::size_t>(x) * s + s / 2;
            const float mz = map.to_map({dx[i], dy[i], dz[i]}).z;
            small_source[index(x, y)] = all_small || 1.0f - mz * mz < small_sin * small_sin;
          }
        }
      }
    }
  });

  // 2. Splat: every map texel's importance times its solid angle is spread with bilinear (tent)
  // weights over the 2 x 2 table texels around its centre. Energy-conserving where map texels are
  // smaller than table texels (near a lat-long map's poles), where point look-ups would miss a small
  // bright texel or over-count it. A map texel taller or wider than half a table texel is split into
  // sub-texels first (each with its exact solid angle), so the splat stays smooth.
  // Rows are processed in chunks: parallel mapping, serial accumulation.
  std::vector<double> splat(total, 0.0);
  const double table_side = std::sqrt(table_texel_sr);
  // Sub-texel splits only where the splat is used (map texels smaller than half a table texel);
  // elsewhere one point per map texel is enough for the splat's role as a fallback.
  auto splits = [&](int y, int& kx, int& ky) {
    const double theta = kPi * (y + 0.5) / h;
    const double height = latlong ? kPi / h : std::sqrt(ea_src_sr);
    const double width = latlong ? 2.0 * kPi / w * std::max(std::sin(theta), std::sin(0.5 * kPi / h))
                                 : std::sqrt(ea_src_sr);
    kx = ky = 1;
    if (width * height >= table_texel_sr) return;  // 2x margin over the small-texel threshold
    kx = std::clamp(static_cast<int>(std::ceil(2.0 * width / table_side)), 1, 16);
    ky = std::clamp(static_cast<int>(std::ceil(2.0 * height / table_side)), 1, 16);
  };
  // Azimuth sines and cosines of the map's column centres (lat-long, one split per column).
  std::vector<float> col_cos(w), col_sin(w);
  for (int x = 0; x < w; ++x) {
    const double phi = 2.0 * kPi * (x + 0.5) / w;
    col_cos[x] = static_cast<float>(std::cos(phi));
    col_sin[x] = static_cast<float>(std::sin(phi));
  }
  struct Row {
    std::vector<float> u, v, e;
  };
  const int chunk = std::max(1, std::min(h, (1 << 18) / w));
  std::vector<Row> rows_out(chunk);
  for (int y0 = 0; y0 < h; y0 += chunk) {
    const int y1 = std::min(h, y0 + chunk);
    tbb::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& rows) {
      std::vector<float> mx, my, mz;
      for (int y = rows.begin(); y < rows.end(); ++y) {
        int kx, ky;
        splits(y, kx, ky);
        Row& out = rows_out[y - y0];
        const std::size_t m = static_cast<std::size_t>(w) * kx * ky;
        mx.resize(m);
        my.resize(m);
        mz.resize(m);
        out.u.resize(m);
        out.v.resize(m);
        out.e.resize(m);
        std::size_t k = 0;
        for (int j = 0; j < ky; ++j) {
          const double v0 = (y + double(j) / ky) / h, v1 = (y + double(j + 1) / ky) / h;
          const double sub_sr = latlong ? 2.0 * kPi / (double(w) * kx) * (std::cos(kPi * v0) - std::cos(kPi * v1))
                                        : ea_src_sr / (double(kx) * ky);
          const float st = static_cast<float>(std::sin(kPi * 0.5 * (v0 + v1)));
          const float ct = static_cast<float>(std::cos(kPi * 0.5 * (v0 + v1)));
          for (int x = 0; x < w; ++x) {
            const float e = static_cast<float>(double(lum_at(x, y)) * sub_sr);
            for (int i = 0; i < kx; ++i, ++k) {
              Vec3 md;
              if (latlong && kx == 1) {
                md = {st * col_cos[x], st * col_sin[x], ct};
              } else {
                const Point2 uv{float((x + (i + 0.5) / kx) / w), float(0.5 * (v0 + v1))};
                md = latlong ? latlong_to_direction(uv) : equal_area_square_to_sphere(uv);
              }
              const Vec3 d = map.to_world(md);
              mx[k] = d.x;
              my[k] = d.y;
              mz[k] = d.z;
              out.e[k] = e;
            }
          }
        }
        equal_area_sphere_to_square(m, mx.data(), my.data(), mz.data(), out.u.data(), out.v.data());
      }
    });
    for (int y = y0; y < y1; ++y) {
      const Row& r = rows_out[y - y0];
      for (std::size_t k = 0; k < r.e.size(); ++k) {
        if (!(r.e[k] > 0)) continue;
        const float px = r.u[k] * N_ - 0.5f, py = r.v[k] * N_ - 0.5f;
        const float fx = std::floor(px), fy = std::floor(py);
        const float tx = px - fx, ty = py - fy;
        const int x0 = static_cast<int>(fx), y0t = static_cast<int>(fy);
        const double e = r.e[k];
        if (x0 >= 0 && y0t >= 0 && x0 + 1 < N_ && y0t + 1 < N_) {  // interior: no wrapping
          splat[index(x0, y0t)] += e * ((1 - tx) * (1 - ty));
          splat[index(x0 + 1, y0t)] += e * (tx * (1 - ty));
          splat[index(x0, y0t + 1)] += e * ((1 - tx) * ty);
          splat[index(x0 + 1, y0t + 1)] += e * (tx * ty);
          continue;
        }
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) {
            int xi = x0 + i, yi = y0t + j;
            if (!equal_area_wrap(N_, xi, yi)) continue;
            splat[index(xi, yi)] += e * ((i ? tx : 1 - tx) * (j ? ty : 1 - ty));
          }
      }
    }
  }
  // Is the map constant? (Then a compensated table is the plain one.)
  float lo = std::numeric_limits<float>::max(), hi = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float a = map.texel(x, y).average();
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
  if (hi - lo <= 1e-6f * hi) compensated = false;

  // 3. Combine: splat where map texels are small, gather elsewhere; either one where the other is 0
  // (so a texel that sees light by either route keeps a positive density).
  func_.assign(total, 0.0f);
  for (std::size_t i = 0; i < total; ++i) {
    const double sp = splat[i] / table_texel_sr, ga = gather[i];
    double v = small_source[i] ? (sp > 0 ? sp : ga) : (ga > 0 ? ga : sp);
    func_[i] = static_cast<float>(std::min<double>(v, std::numeric_limits<float>::max()));
  }
  // 4. Peak bound: at least 1/K of the largest radiance eval returns inside the texel (texel_peak.h).
  if (peak_ratio > 0) {
    const std::vector<float> peaks = detail::texel_peaks(map, lum, N_);
    const float inv_k = 1.0f / peak_ratio;
    for (int y = 0; y < N_; ++y)
      for (int x = 0; x < N_; ++x) {
        float& v = func_[index(x, y)];
        v = std::max(v, peaks[static_cast<std::size_t>(y) * N_ + x] * inv_k);
      }
  }
  double sum = 0;
  for (float v : func_) sum += v;
  empty_ = !(sum > 0) || !std::isfinite(sum);
  if (empty_) {
    std::fill(func_.begin(), func_.end(), 0.0f);
    integral_ = 0;
    return;
  }
  if (compensated) {
    const float mean = static_cast<float>(sum / double(total));
    double csum = 0;
    for (float v : func_) csum += std::max(0.0f, v - mean);
    if (csum > 0) {
      for (float& v : func_) v = std::max(0.0f, v - mean);
      integral_ = csum * table_texel_sr;
      return;
    }
  }
  // 3. Floor: positive density everywhere.
  const float min_value = static_cast<float>(floor * sum / double(total));
  if (min_value > 0) {
    sum = 0;
    for (float& v : func_) {
      v = std::max(v, min_value);
      sum += v;
    }
  }
  integral_ = sum * table_texel_sr;
}

void ImportanceTable::build_cells() {
  const int cells = T_ * T_;
  const std::size_t per_cell = static_cast<std::size_t>(F_) * F_;
  cdf_.assign(func_.size(), 0.0f);
  cell_sum_.assign(cells, 0.0f);
  cell_prob_.assign(cells, 0.0f);
  std::vector<double> sums(cells, 0.0);
  tbb::parallel_for(tbb::blocked_range<int>(0, cells), [&](const tbb::blocked_range<int>& range) {
    std::vector<float> cdf(per_cell);  // row-major running sums, normalized to end at 1
    for (int c = range.begin(); c < range.end(); ++c) {
      const float* f = &func_[c * per_cell];
      double total_c = 0;
      for (std::size_t i = 0; i < per_cell; ++i) total_c += f[i];
      sums[c] = total_c;
      if (total_c > 0) {
        double run = 0;
        for (std::size_t i = 0; i < per_cell; ++i) cdf[i] = static_cast<float>((run += f[i]) / total_c);
      } else {  // a zero cell (only with floor 0): uniform, never chosen because its probability is 0
        for (std::size_t i = 0; i < per_cell; ++i) cdf[i] = float(i + 1) / float(per_cell);
      }
      cdf[per_cell - 1] = 1.0f;
      detail::store_split2d(cdf.data(), F_, F_, &cdf_[c * per_cell]);
    }
  });
  double total = 0;
  for (double s : sums) total += s;
  for (int c = 0; c < cells; ++c) {
    cell_sum_[c] = static_cast<float>(sums[c]);
    cell_prob_[c] = total > 0 ? static_cast<float>(sums[c] / total) : 0.0f;
  }
  // Top-level row totals and their running sums for environment-only sampling (the same layout and
  // search as the product sampler's: a row, then a scan of its cells).
  top_row_sum_.assign(T_, 0.0f);
  top_row_cdf_.assign(T_, 0.0f);
  detail::store_row_sums(cell_prob_.data(), T_, T_, top_row_sum_.data(), top_row_cdf_.data());
  padded_ = (cells + 15) / 16 * 16;
  for (auto& a : soa_) a.assign(padded_, 0.0f);
  for (int c = 0; c < cells; ++c) soa_[5][c] = cell_prob_[c];
}

void ImportanceTable::build_cones() {
  const int cells = T_ * T_;
  cones_.assign(cells, Cone{});
  constexpr int kEdge = 256;  // boundary samples per cell edge
  constexpr int kInner = 16;  // interior grid for the axis
  tbb::parallel_for(0, cells, [&](int c) {
    const int cx = c % T_, cy = c / T_;
    const float x0 = float(cx) / T_, y0 = float(cy) / T_, side = 1.0f / T_;
    Cone cone;
    if (T_ <= 2) {  // cells of a quarter sphere or more: use the whole sphere
      cone.axis = equal_area_square_to_sphere({x0 + 0.5f * side, y0 + 0.5f * side});
      cone.cos_half_angle = -1.0f;
      cone.sin_half_angle = 0.0f;
      cones_[c] = cone;
      return;
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
    double max_angle = 0, max_gap = 0;
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
      max_angle = std::max(max_angle, std::acos(std::clamp(double(dot(d, axis)), -1.0, 1.0)));
      max_gap = std::max(max_gap, std::acos(std::clamp(double(dot(d, prev)), -1.0, 1.0)));
      prev = d;
    }
    const double b = std::min(max_angle + 0.5 * max_gap + 1e-4, double(kPi));
    cone.axis = axis;
    cone.cos_half_angle = static_cast<float>(std::cos(b));
    cone.sin_half_angle = static_cast<float>(std::sin(b));
    cones_[c] = cone;
  });
  for (int c = 0; c < cells; ++c) {
    soa_[0][c] = cones_[c].axis.x;
    soa_[1][c] = cones_[c].axis.y;
    soa_[2][c] = cones_[c].axis.z;
    soa_[3][c] = cones_[c].cos_half_angle;
    soa_[4][c] = cones_[c].sin_half_angle;
  }
  // Padding cells: probability 0, a cone that evaluates harmlessly.
  for (int c = cells; c < padded_; ++c) {
    soa_[2][c] = 1.0f;
    soa_[3][c] = 1.0f;
  }
}

int ImportanceTable::cell_of(Point2 p) const {
  const int cx = std::clamp(static_cast<int>(p.x * T_), 0, T_ - 1);
  const int cy = std::clamp(static_cast<int>(p.y * T_), 0, T_ - 1);
  return cy * T_ + cx;
}

int ImportanceTable::cell_of_direction(Vec3 d) const {
  if (!is_valid_direction(d)) return -1;
  return cell_of(equal_area_sphere_to_square(d));
}

Point2 ImportanceTable::sample_in_cell(int c, Point2 u, float* pdf_in_cell, bool* interior) const {
  const std::size_t per_cell = static_cast<std::size_t>(F_) * F_;
  const float* cdf = &cdf_[c * per_cell];
  const detail::Flat2DSample s = detail::sample_split2d(cdf, F_, F_, u);
  const int cx = c % T_, cy = c / T_;
  if (pdf_in_cell) {
    const float f = func_[c * per_cell + static_cast<std::size_t>(s.y) * F_ + s.x];
    *pdf_in_cell = cell_sum_[c] > 0 ? f / cell_sum_[c] * float(F_) * float(F_) : 0.0f;
  }
  if (interior) {
    // The square -> sphere -> square round trip is accurate to a few 1e-6 (tests/test_equal_area.cpp);
    // 2% of a texel is at least 7e-6 for N <= 2904 and scales with the texel.
    constexpr float kMargin = 0.02f;
    *interior = s.ox > kMargin && s.ox < 1 - kMargin && s.oy > kMargin && s.oy < 1 - kMargin && N_ <= 2904;
  }
  // Keep the point kEdge inside its top cell. Rounding can put it on the cell's far edge (an offset
  // of 1 - 2^-24 in the last texel), and a point within round-off of the edge can come back from
  // square -> sphere -> square in the neighbouring cell, whose product weight may be 0 (a cell wholly
  // below an opaque proxy's horizon): the sample would get pdf 0 where pdf() integrates to 1. The
  // move is under 2% of a texel for N <= 1000 and such samples are never `interior`, so their pdf is
  // pdf(direction), which finds this cell.
  constexpr float kEdge = 2e-5f;
  const float inv_T = 1.0f / float(T_);
  const float px = (float(cx * F_ + s.x) + s.ox) / float(N_), py = (float(cy * F_ + s.y) + s.oy) / float(N_);
  return {std::clamp(px, float(cx) * inv_T + kEdge, float(cx + 1) * inv_T - kEdge),
          std::clamp(py, float(cy) * inv_T + kEdge, float(cy + 1) * inv_T - kEdge)};
}

float ImportanceTable::pdf_in_cell(int c, Point2 p) const {
  const int x = std::clamp(static_cast<int>(p.x * N_), 0, N_ - 1);
  const int y = std::clamp(static_cast<int>(p.y * N_), 0, N_ - 1);
  // p may sit on the cell's boundary through rounding: clamp into the cell.
  const int cx = c % T_, cy = c / T_;
  const int xc = std::clamp(x, cx * F_, cx * F_ + F_ - 1), yc = std::clamp(y, cy * F_, cy * F_ + F_ - 1);
  if (!(cell_sum_[c] > 0)) return 0.0f;
  return func_[texel_index(xc, yc)] / cell_sum_[c] * float(F_) * float(F_);
}

DirectionSample ImportanceTable::sample(Point2 u) const {
  DirectionSample out;
  if (empty_) return out;
  const detail::Flat2DSample s = detail::sample_row_scan(top_row_cdf_.data(), top_row_sum_.data(), cell_prob_.data(),
                                                          T_, T_, u, top_row_cdf_[T_ - 1]);
  const int c = s.y * T_ + s.x;
  float pc;
  bool interior;
  const Point2 p = sample_in_cell(c, {s.ox, s.oy}, &pc, &interior);
  out.direction = equal_area_square_to_sphere(p);
  out.cell = c;
  // Far from texel edges the sampled texel is the one pdf() finds: its density directly (same
  // arithmetic as pdf()); near an edge, pdf() of the direction, so the two always agree.
  out.pdf = interior ? cell_prob_[c] * pc * float(T_) * float(T_) * kInv4Pi : pdf(out.direction);
  return out;
}

float ImportanceTable::pdf(Vec3 d) const {
  if (empty_ || !is_valid_direction(d)) return 0.0f;
  const Point2 p = equal_area_sphere_to_square(d);
  const int c = cell_of(p);
  return cell_prob_[c] * pdf_in_cell(c, p) * float(T_) * float(T_) * kInv4Pi;
}

std::size_t ImportanceTable::bytes_used() const {
  std::size_t b = sizeof(*this);
  b += func_.capacity() * sizeof(float) + cdf_.capacity() * sizeof(float);
  b += (cell_sum_.capacity() + cell_prob_.capacity() + top_row_sum_.capacity() + top_row_cdf_.capacity()) *
       sizeof(float);
  b += cones_.capacity() * sizeof(Cone);
  for (const auto& a : soa_) b += a.capacity() * sizeof(float);
  return b;
}

std::size_t ImportanceTable::single_level_bytes() const {
  const std::size_t n = static_cast<std::size_t>(N_);
  return sizeof(float) * (n * n + n * (n + 1) + n + (n + 1));
}

}  // namespace envpis
