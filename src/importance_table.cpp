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

namespace envpis {

namespace {
constexpr int kMaxTop = 256;
constexpr int kMaxFine = 16384;
}  // namespace

ImportanceTable::ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.top_resolution < 1 || options.top_resolution > kMaxTop)
    throw Error("top-level resolution must be in 1.." + std::to_string(kMaxTop) + ", got " +
                std::to_string(options.top_resolution));
  if (options.fine_resolution < 0 || options.fine_resolution > kMaxFine)
    throw Error("fine resolution must be 0 (automatic) or in 1.." + std::to_string(kMaxFine));
  if (!(options.floor >= 0.0f && options.floor < 1.0f))
    throw Error("importance floor must be in [0, 1)");
  T_ = options.top_resolution;
  int n = options.fine_resolution;
  if (n == 0) {
    const double texels = double(map.width()) * double(map.height());
    n = static_cast<int>(std::ceil(std::sqrt(texels) - 1e-9));
  }
  F_ = std::max(1, (n + T_ - 1) / T_);
  N_ = T_ * F_;
  if (N_ > kMaxFine) {
    F_ = kMaxFine / T_;
    N_ = T_ * F_;
  }
  build_importance(map, options.floor);
  build_cells();
  build_cones();
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::size_t ImportanceTable::texel_index(int x, int y) const {
  const int cx = x / F_, cy = y / F_, lx = x - cx * F_, ly = y - cy * F_;
  return ((static_cast<std::size_t>(cy) * T_ + cx) * F_ + ly) * F_ + lx;
}

float ImportanceTable::importance(int x, int y) const { return func_[texel_index(x, y)]; }

void ImportanceTable::build_importance(const EnvironmentMap& map, float floor) {
  const std::size_t total = static_cast<std::size_t>(N_) * N_;
  func_.assign(total, 0.0f);
  // 1. Average of stratified bilinear look-ups over each table texel.
  const double ratio = double(map.width()) * map.height() / double(total);
  const int s = std::clamp(static_cast<int>(std::ceil(2.0 * std::sqrt(ratio))), 2, 8);
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
            const Rgb L = map.eval({dx[i], dy[i], dz[i]});
            acc += (double(L.r) + L.g + L.b) / 3.0;
          }
          func_[texel_index(x, y)] += static_cast<float>(acc / (double(s) * s));
        }
      }
    }
  });
  // 2. Splat every map texel (importance times its solid angle) into the table texel holding its
  // centre, so that texels much smaller than a table texel (near a lat-long map's poles) are never
  // missed by the point look-ups above.
  const int w = map.width(), h = map.height();
  std::vector<std::uint32_t> dest(static_cast<std::size_t>(w) * h);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        const Point2 uv{(x + 0.5f) / w, (y + 0.5f) / h};
        const Vec3 md = map.layout() == MapLayout::EqualArea ? equal_area_square_to_sphere(uv)
                                                               : latlong_to_direction(uv);
        const Point2 p = equal_area_sphere_to_square(map.to_world(md));
        const int tx = std::min(static_cast<int>(p.x * N_), N_ - 1);
        const int ty = std::min(static_cast<int>(p.y * N_), N_ - 1);
        dest[static_cast<std::size_t>(y) * w + x] = static_cast<std::uint32_t>(texel_index(tx, ty));
      }
  });
  std::vector<double> splat(total, 0.0);
  const double table_texel_sr = 4.0 * kPi / double(total);
  for (int y = 0; y < h; ++y) {
    double texel_sr;
    if (map.layout() == MapLayout::EqualArea) {
      texel_sr = 4.0 * kPi / (double(w) * h);
    } else {
      const double t0 = kPi * double(y) / h, t1 = kPi * double(y + 1) / h;
      texel_sr = 2.0 * kPi / w * (std::cos(t0) - std::cos(t1));
    }
    for (int x = 0; x < w; ++x) {
      const Rgb L = map.texel(x, y);
      splat[dest[static_cast<std::size_t>(y) * w + x]] += (double(L.r) + L.g + L.b) / 3.0 * texel_sr;
    }
  }
  double sum = 0;
  for (std::size_t i = 0; i < total; ++i) {
    const double v = std::max<double>(func_[i], splat[i] / table_texel_sr);
    func_[i] = static_cast<float>(std::min<double>(v, std::numeric_limits<float>::max()));
    sum += func_[i];
  }
  empty_ = !(sum > 0) || !std::isfinite(sum);
  if (empty_) {
    std::fill(func_.begin(), func_.end(), 0.0f);
    integral_ = 0;
    return;
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
  tbb::parallel_for(0, cells, [&](int c) {
    const float* f = &func_[c * per_cell];
    float* cdf = &cdf_[c * per_cell];
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
  });
  double total = 0;
  for (double s : sums) total += s;
  for (int c = 0; c < cells; ++c) {
    cell_sum_[c] = static_cast<float>(sums[c]);
    cell_prob_[c] = total > 0 ? static_cast<float>(sums[c] / total) : 0.0f;
  }
  // Top-level running sums for environment-only sampling.
  top_cdf_.assign(cells, 0.0f);
  double run = 0;
  for (int c = 0; c < cells; ++c) top_cdf_[c] = total > 0 ? static_cast<float>((run += sums[c]) / total) : 0.0f;
  const float last = top_cdf_[cells - 1];
  for (int c = cells - 1; c >= 0 && top_cdf_[c] >= last; --c) top_cdf_[c] = 1.0f;
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

Point2 ImportanceTable::sample_in_cell(int c, Point2 u, float* pdf_in_cell) const {
  const std::size_t per_cell = static_cast<std::size_t>(F_) * F_;
  const float* cdf = &cdf_[c * per_cell];
  const detail::Flat2DSample s = detail::sample_flat2d(cdf, F_, F_, u);
  const int cx = c % T_, cy = c / T_;
  if (pdf_in_cell) {
    const float f = func_[c * per_cell + static_cast<std::size_t>(s.y) * F_ + s.x];
    *pdf_in_cell = cell_sum_[c] > 0 ? f / cell_sum_[c] * float(per_cell) : 0.0f;
  }
  return {(float(cx * F_ + s.x) + s.ox) / float(N_), (float(cy * F_ + s.y) + s.oy) / float(N_)};
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
  const detail::Flat2DSample s = detail::sample_flat2d(top_cdf_.data(), T_, T_, u);
  const int c = s.y * T_ + s.x;
  const Point2 p = sample_in_cell(c, {s.ox, s.oy}, nullptr);
  out.direction = equal_area_square_to_sphere(p);
  out.cell = c;
  out.pdf = pdf(out.direction);
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
  b += (cell_sum_.capacity() + cell_prob_.capacity() + top_cdf_.capacity()) * sizeof(float);
  b += cones_.capacity() * sizeof(Cone);
  for (const auto& a : soa_) b += a.capacity() * sizeof(float);
  return b;
}

std::size_t ImportanceTable::single_level_bytes() const {
  const std::size_t n = static_cast<std::size_t>(N_);
  return sizeof(float) * (n * n + n * (n + 1) + n + (n + 1));
}

}  // namespace envpis
