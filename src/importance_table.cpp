#include "envpis/importance_table.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "envpis_assert.h"
#include "envpis/equal_area.h"
#include "fine_level.h"
#include "kernels.h"
#include "parallel.h"
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
  auto fine = std::make_shared<detail::FineLevel>(T_, F_);
  fine_ = fine;
  build_importance(map, options.floor, options.peak_ratio, options.compensated, fine->values());
  build_top_level(fine->build());
  build_cones();
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

float ImportanceTable::importance(int x, int y) const { return fine_->values()[fine_->index(x, y)]; }

void ImportanceTable::build_importance(const EnvironmentMap& map, float floor, float peak_ratio, bool compensated,
                                       std::vector<float>& func) {
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
  detail::parallel_for(0, N_, [&](int row_begin, int row_end) {
    const std::size_t m = static_cast<std::size_t>(N_) * s;
    std::vector<float> pu(m), pv(m), dx(m), dy(m), dz(m);
    for (int y = row_begin; y < row_end; ++y) {
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
    detail::parallel_for(y0, y1, [&](int row_begin, int row_end) {
      std::vector<float> mx, my, mz;
      for (int y = row_begin; y < row_end; ++y) {
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
  func.assign(total, 0.0f);
  for (std::size_t i = 0; i < total; ++i) {
    const double sp = splat[i] / table_texel_sr, ga = gather[i];
    double v = small_source[i] ? (sp > 0 ? sp : ga) : (ga > 0 ? ga : sp);
    func[i] = static_cast<float>(std::min<double>(v, std::numeric_limits<float>::max()));
  }
  // 4. Peak bound: at least 1/K of the largest radiance eval returns inside the texel (texel_peak.h).
  if (peak_ratio > 0) {
    const std::vector<float> peaks = detail::texel_peaks(map, lum, N_);
    const float inv_k = 1.0f / peak_ratio;
    for (int y = 0; y < N_; ++y)
      for (int x = 0; x < N_; ++x) {
        float& v = func[index(x, y)];
        v = std::max(v, peaks[static_cast<std::size_t>(y) * N_ + x] * inv_k);
      }
  }
  double sum = 0;
  for (float v : func) sum += v;
  empty_ = !(sum > 0) || !std::isfinite(sum);
  if (empty_) {
    std::fill(func.begin(), func.end(), 0.0f);
    integral_ = 0;
    return;
  }
  if (compensated) {
    const float mean = static_cast<float>(sum / double(total));
    double csum = 0;
    for (float v : func) csum += std::max(0.0f, v - mean);
    if (csum > 0) {
      for (float& v : func) v = std::max(0.0f, v - mean);
      integral_ = csum * table_texel_sr;
      return;
    }
  }
  // 3. Floor: positive density everywhere.
  const float min_value = static_cast<float>(floor * sum / double(total));
  if (min_value > 0) {
    sum = 0;
    for (float& v : func) {
      v = std::max(v, min_value);
      sum += v;
    }
  }
  integral_ = sum * table_texel_sr;
}

void ImportanceTable::build_top_level(const std::vector<double>& cell_sums) {
  const int cells = T_ * T_;
  double total = 0;
  for (double v : cell_sums) total += v;
  top_ = DiscreteDistribution2D(T_, T_);
  for (int c = 0; c < cells; ++c) top_.values()[c] = total > 0 ? static_cast<float>(cell_sums[c] / total) : 0.0f;
  top_.update();
  for (auto& a : soa_) a.assign(static_cast<std::size_t>(top_.padded_size()), 0.0f);
  for (int c = 0; c < cells; ++c) soa_[5][c] = top_.values()[c];
}

namespace {
// A cone that contains every direction of top cell c of a T x T grid on the equal-area square.
Cone bounding_cone(int T, int c) {
  constexpr int kEdge = 256;  // boundary samples per cell edge
  constexpr int kInner = 16;  // interior grid for the axis
  const int cx = c % T, cy = c / T;
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
  return cone;
}
}  // namespace

void ImportanceTable::build_cones() {
  const int cells = T_ * T_;
  cones_.assign(cells, Cone{});
  detail::parallel_for(0, cells, [&](int begin, int end) {
    for (int c = begin; c < end; ++c) cones_[c] = bounding_cone(T_, c);
  });
  for (int c = 0; c < cells; ++c) {
    soa_[0][c] = cones_[c].axis.x;
    soa_[1][c] = cones_[c].axis.y;
    soa_[2][c] = cones_[c].axis.z;
    soa_[3][c] = cones_[c].cos_half_angle;
    soa_[4][c] = cones_[c].sin_half_angle;
  }
  // Padding cells: probability 0, a cone that evaluates harmlessly.
  for (int c = cells; c < top_.padded_size(); ++c) {
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

float ImportanceTable::pdf_in_cell(int c, Point2 p) const { return fine_->pdf(c, p); }

DirectionSample ImportanceTable::sample(const DiscreteDistribution2D& top, Point2 u) const {
  DirectionSample out;
  if (empty_ || !top.valid()) return out;
  ENVPIS_ASSERT(top.width() == T_ && top.height() == T_);
  const DiscreteDistribution2D::Sample cell = top.sample(u);
  const int c = cell.y * T_ + cell.x;
  const detail::FineLevel::Sample s = fine_->sample(c, cell.offset);
  out.direction = equal_area_square_to_sphere(s.p);
  out.cell = c;
  // Far from texel edges the sampled texel is the one pdf() finds: its density directly (the same
  // arithmetic); near an edge, pdf() of the direction, so the two always agree.
  out.pdf = s.interior ? solid_angle_pdf(cell.pmf, s.pdf) : pdf(top, out.direction);
  return out;
}

float ImportanceTable::pdf(const DiscreteDistribution2D& top, Vec3 d) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return 0.0f;
  const Point2 p = equal_area_sphere_to_square(d);
  const int c = cell_of(p);
  return solid_angle_pdf(top.pmf(c), fine_->pdf(c, p));
}

Point2 ImportanceTable::invert(const DiscreteDistribution2D& top, Vec3 d) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return {0.5f, 0.5f};
  const Point2 p = equal_area_sphere_to_square(d);
  const int c = cell_of(p);
  return top.invert(c % T_, c / T_, fine_->invert(c, p));
}

detail::CellArrays detail::cell_arrays(const ImportanceTable& t) {
  const auto& a = t.soa_;
  return {a[0].data(), a[1].data(), a[2].data(), a[3].data(), a[4].data(), a[5].data(), t.top_.padded_size()};
}

std::size_t ImportanceTable::bytes_used() const {
  std::size_t b = sizeof(*this);
  b += fine_->bytes_used();
  b += static_cast<std::size_t>(top_.padded_size() + 2 * T_) * sizeof(float);
  b += cones_.capacity() * sizeof(Cone);
  for (const auto& a : soa_) b += a.capacity() * sizeof(float);
  return b;
}

std::size_t ImportanceTable::single_level_bytes() const {
  const std::size_t n = static_cast<std::size_t>(N_);
  return sizeof(float) * (n * n + n * (n + 1) + n + (n + 1));
}

}  // namespace envpis
