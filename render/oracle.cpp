// SPDX-License-Identifier: Apache-2.0
#include "render/oracle.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "render/hash.h"

namespace envpis::render {

namespace {
// Every cell a light sample can use keeps at least this fraction of its environment share (relative
// to the estimated total): a cell whose points all missed is then sampled rarely, never not at all.
constexpr double kFloor = 1e-3;
// With MIS compensation, a cell keeps at least this fraction of its estimated share.
constexpr double kKeep = 0.25;
// Points per side with which a fine texel's mean radiance is computed.
constexpr int kTexelSide = 2;
// First-pass points per side in a cell that straddles the surface's horizon (when directions below it
// count nothing): its brightest texels may lie below, and a point there tells nothing of the rest.
constexpr int kHorizonSide = 4;
// At most this many points per side in one cell's refinement.
constexpr int kMaxRefineSide = 32;
// Share of a cell's texel distribution that follows the table's importance inside the cell: every
// texel with importance keeps a light density, so no direction with radiance depends on the BSDF
// sample alone, and a cell whose texels all weigh 0 (below the horizon, f = 0) is still a distribution.
constexpr double kTexelMix = 0.01;
// The first pass loads the row search's data of the cell this many cells ahead.
constexpr std::size_t kPrefetchCells = 8;

// The weight under MIS compensation of a cell or a texel whose share of the estimated integral is
// `share` and which the BSDF sample reaches with probability p_bsdf (or: both as densities).
double compensated(double share, double p_bsdf) { return std::max(kKeep * share, 2 * share - p_bsdf); }

float unit_from_bits(std::uint64_t bits) { return float(bits & 0xffffff) * 0x1p-24f; }
// Two independent uniform numbers from a hash of the shading point's jitter and a key.
Point2 offset(std::uint64_t jitter, std::uint64_t key) {
  const std::uint64_t h = mix64(jitter ^ mix64(key + 0x632be59bd9b4e019ULL));
  return {unit_from_bits(h >> 40), unit_from_bits(h >> 8)};
}
}  // namespace

OracleCells::OracleCells(const EnvironmentMap& env, std::shared_ptr<const ImportanceTable> table)
    : table_(std::move(table)) {
  const int T = table_->top_resolution(), F = table_->cell_resolution(), N = table_->fine_resolution();
  cells_.resize(static_cast<std::size_t>(T) * T);
  radiance_.resize(static_cast<std::size_t>(N) * N);
  tbb::parallel_for(0, T * T, [&](int c) {
    std::vector<float> values(static_cast<std::size_t>(F) * F);
    const int x0 = (c % T) * F, y0 = (c / T) * F;
    for (int y = 0; y < F; ++y)
      for (int x = 0; x < F; ++x) {
        // The texel's mean radiance, from kTexelSide^2 stratified points.
        Rgb sum;
        for (int j = 0; j < kTexelSide; ++j)
          for (int i = 0; i < kTexelSide; ++i)
            sum = sum + env.eval(equal_area_square_to_sphere({(float(x0 + x) + (float(i) + 0.5f) / kTexelSide) / float(N),
                                                              (float(y0 + y) + (float(j) + 0.5f) / kTexelSide) / float(N)}));
        radiance_[index(c, x, y)] = sum * (1.0f / float(kTexelSide * kTexelSide));
        values[static_cast<std::size_t>(y) * F + x] = radiance_[index(c, x, y)].average();
      }
    cells_[static_cast<std::size_t>(c)] = DiscreteDistribution2D(values.data(), F, F);
  });
}

OracleSampler::OracleSampler(std::shared_ptr<const OracleCells> cells, const OracleOptions& options)
    : cells_(std::move(cells)), options_(options) {
  const int T = cells_->table().top_resolution();
  const std::size_t n = static_cast<std::size_t>(T) * T;
  top_ = DiscreteDistribution2D(T, T);
  count_.resize(n);
  cell_sum_.resize(n);
  bsdf_mass_.resize(n);
  weight_.resize(n);
  active_.reserve(n);
  slot_.assign(n, -1);
}

OracleSampler::Point OracleSampler::evaluate(const ShadingContext& sc, Point2 sq, int c, float q, Rgb radiance,
                                             bool skip_below) const {
  const Vec3 wi = equal_area_square_to_sphere(sq);
  const Vec3 wl = sc.frame->to_local(wi);
  Point p{c, 0.0f, q, 0.0f};
  if (skip_below && !(wl.z > 0)) {
    p.pb = sc.bsdf->pdf(sc.wo_local, wl);
    return p;
  }
  const Rgb f = sc.bsdf->eval_pdf(sc.wo_local, wl, &p.pb);
  if (!(f.average() > 0)) return p;
  const float g = (f * radiance).average() * std::fabs(wl.z);
  p.g = std::isfinite(g) && g > 0 ? g : 0.0f;
  return p;
}

// Draws k x k points in cell c in three steps, each over the draws of many cells, so that the cache
// misses of a step overlap (each cell's distribution and the texels' radiance are spread over tens of
// MB; the misses were most of prepare's time): the rows here (one search per row of strata), then the
// texels in the rows (place_draws), then the evaluation (evaluate_draws). The next step's data is
// prefetched by each.
void OracleSampler::light_points(const ShadingContext& sc, int c, int k, int pass) {
  const DiscreteDistribution2D& d = cells_->cell(c);
  if (!d.valid()) return;
  const float inv_k = 1.0f / float(k);
  // Every cell and pass its own random offset of the k x k strata.
  const Point2 o = offset(sc.jitter, std::uint64_t(c) * 2 + std::uint64_t(pass) + 1);
  for (int j = 0; j < k; ++j) {
    const DiscreteDistribution2D::Sample s = d.sample_row((float(j) + o.y) * inv_k);
    d.prefetch_row(s.y);
    for (int i = 0; i < k; ++i) rows_.push_back({c, (float(i) + o.x) * inv_k, s});
  }
  count_[static_cast<std::size_t>(c)] += k * k;
}

void OracleSampler::place_draws() {
  const ImportanceTable& t = cells_->table();
  const int T = t.top_resolution(), F = t.cell_resolution(), N = t.fine_resolution();
  const float inv_n = 1.0f / float(N);
  const float to_solid_angle = t.solid_angle_pdf(1.0f, float(F) * float(F));  // a fine texel: 4 pi / N^2 sr
  for (RowDraw& r : rows_) {
    DiscreteDistribution2D::Sample& s = r.s;
    cells_->cell(r.cell).sample_in_row(r.ux, &s);
    const int x0 = (r.cell % T) * F, y0 = (r.cell / T) * F;
    const Point2 p{(float(x0 + s.x) + s.offset.x) * inv_n, (float(y0 + s.y) + s.offset.y) * inv_n};
    const Rgb* radiance = &cells_->radiance(r.cell, s.x, s.y);
    __builtin_prefetch(radiance);
    draws_.push_back({r.cell, p, s.pmf * to_solid_angle, radiance});
  }
  rows_.clear();
}

void OracleSampler::evaluate_draws(const ShadingContext& sc) {
  const bool skip_below = sc.opaque || sc.bsdf->closed_surface();
  for (const Draw& d : draws_) points_.push_back(evaluate(sc, d.p, d.cell, d.q, *d.radiance, skip_below));
  draws_.clear();
}

// The balance heuristic over every point of the cell: the cell's points from its fine distribution
// (count_ of them, density q) and the shading point's BSDF samples (options_.bsdf_samples, density pb).
void OracleSampler::estimate() {
  std::fill(cell_sum_.begin(), cell_sum_.end(), 0.0);
  std::fill(bsdf_mass_.begin(), bsdf_mass_.end(), 0.0);
  const double m = double(options_.bsdf_samples);
  for (const Point& p : points_) {
    const double d = double(count_[static_cast<std::size_t>(p.cell)]) * p.q + m * p.pb;
    if (!(d > 0)) continue;
    cell_sum_[static_cast<std::size_t>(p.cell)] += p.g / d;
    bsdf_mass_[static_cast<std::size_t>(p.cell)] += p.pb / d;
  }
}

void OracleSampler::prepare(const ShadingContext& sc) {
  valid_ = false;
  sc_ = sc;
  for (int c : built_) slot_[static_cast<std::size_t>(c)] = -1;
  built_.clear();
  const ImportanceTable& t = cells_->table();
  if (t.empty()) return;
  const int cells = t.cell_count();
  const int T = t.top_resolution(), F = t.cell_resolution(), N = t.fine_resolution();
  const float to_solid_angle = t.solid_angle_pdf(1.0f, float(F) * float(F));  // a fine texel: 4 pi / N^2 sr
  // Directions below the surface carry nothing a light sample can use: for reflection-only materials
  // (f = 0 there), and for closed surfaces, whose local -Z is the inside of the object: a shadow ray
  // into it is always blocked (Material::set_closed_surface; the product proxy leaves out the same
  // lobes, so the oracle stays the limit of the method under the same knowledge).
  const bool skip_below = sc.opaque || sc.bsdf->closed_surface();
  // Cells a light sample can use: positive environment importance, and (when skipping below) a cone
  // not entirely below the surface (angle(axis, n) >= 90 deg + half-angle <=> cos <= -sin(half-angle)).
  active_.clear();
  horizon_.clear();
  for (int c = 0; c < cells; ++c) {
    if (!(t.cell_probability(c) > 0)) continue;
    if (skip_below) {
      const Cone& cone = t.cell_cone(c);
      const float cos_axis = dot(cone.axis, sc.n);
      if (cos_axis <= -cone.sin_half_angle) continue;
      horizon_.push_back(cos_axis < cone.sin_half_angle);
    } else {
      horizon_.push_back(false);
    }
    active_.push_back(c);
  }
  points_.clear();
  rows_.clear();
  draws_.clear();
  std::fill(count_.begin(), count_.end(), 0);
  const Point2 first = offset(sc.jitter, 0), second = offset(sc.jitter, ~std::uint64_t(0));

  // BSDF samples on a stratified grid (the same offset in every stratum).
  const int m = static_cast<int>(std::lround(std::sqrt(double(options_.bsdf_samples))));
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const Point2 u{(float(i) + first.x) / float(m), (float(j) + first.y) / float(m)};
      const float uc = std::fmod(second.x + float(j * m + i) * 0.6180339887f, 1.0f);
      const std::optional<BsdfSample> s = sc.bsdf->sample(sc.wo_local, u, uc);
      if (!s || !(s->pdf > 0)) continue;
      const Vec3 wi = sc.frame->to_world(s->wi);
      const Point2 p = equal_area_sphere_to_square(wi);
      const int c = t.cell_of(p);
      const DiscreteDistribution2D& d = cells_->cell(c);
      if (!d.valid()) continue;  // a black cell: nothing to estimate
      const int x = std::clamp(static_cast<int>(p.x * float(N)) - (c % T) * F, 0, F - 1);
      const int y = std::clamp(static_cast<int>(p.y * float(N)) - (c / T) * F, 0, F - 1);
      points_.push_back(evaluate(sc, p, c, d.pmf(x, y) * to_solid_angle, cells_->radiance(c, x, y), skip_below));
    }
  // First pass: a few points in every cell; then more where the first estimate puts the integral.
  const int k0 = static_cast<int>(std::lround(std::sqrt(double(options_.directions))));
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (a + kPrefetchCells < active_.size()) cells_->cell(active_[a + kPrefetchCells]).prefetch_rows();
    light_points(sc, active_[a], horizon_[a] ? std::max(k0, kHorizonSide) : k0, 0);
  }
  place_draws();
  evaluate_draws(sc);
  estimate();
  double total = 0;
  for (int c : active_) total += cell_sum_[static_cast<std::size_t>(c)];
  if (total > 0 && options_.refine_points > 0) {
    for (int c : active_) {
      const double share = cell_sum_[static_cast<std::size_t>(c)] / total;
      const int k = std::min(kMaxRefineSide, static_cast<int>(std::sqrt(options_.refine_points * share)));
      if (k > 0) light_points(sc, c, k, 1);
    }
    place_draws();
    evaluate_draws(sc);
    estimate();
    total = 0;
    for (int c : active_) total += cell_sum_[static_cast<std::size_t>(c)];
  }
  if (!(total > 0)) return;
  total_ = total;
  float* weight = top_.values();
  std::fill(weight, weight + top_.padded_size(), 0.0f);
  // The weights. With compensation (the light sample is combined with a BSDF sample by MIS): one
  // light and one BSDF sample under the balance heuristic have least variance when p_light + p_bsdf
  // is proportional to the integrand, so a cell's probability plus the BSDF sample's probability of
  // landing in it should be twice its share (Karlik et al. 2019's compensation, on the top level).
  // A cell keeps a quarter of its share: its estimate is noisy, and the BSDF sample covers it only on
  // average over the cell. Every usable cell keeps kFloor of its environment share.
  const bool compensate = options_.mis_compensation;
  for (int c : active_) {
    const std::size_t i = static_cast<std::size_t>(c);
    const double share = cell_sum_[i] / total;
    weight_[i] = compensate ? compensated(share, bsdf_mass_[i]) : share;
  }
  double sum = 0;
  for (int c : active_) sum += weight_[static_cast<std::size_t>(c)];
  if (!(sum > 0) || !std::isfinite(sum)) return;
  for (int c : active_)
    weight[c] = static_cast<float>(std::max(weight_[static_cast<std::size_t>(c)] / sum, kFloor * t.cell_probability(c)));
  top_.update();
  valid_ = top_.valid();
}

// The weights of cell c's texels: each texel's share density of g at its centre (the texel's mean
// radiance), compensated for MIS as the cells are, mixed with the table's importance inside the cell.
void OracleSampler::texel_weights(int c, float* out, const TexelBsdf* given) const {
  const ImportanceTable& t = cells_->table();
  const int T = t.top_resolution(), F = t.cell_resolution(), N = t.fine_resolution();
  const int x0 = (c % T) * F, y0 = (c / T) * F;
  const bool skip_below = sc_.opaque || sc_.bsdf->closed_surface();
  const bool compensate = options_.mis_compensation;
  const double inv_total = 1.0 / total_;
  const float inv_n = 1.0f / float(N);
  double w_sum = 0, q_sum = 0;
  for (int y = 0; y < F; ++y)
    for (int x = 0; x < F; ++x) {
      TexelBsdf b = given ? given[y * F + x] : TexelBsdf{};
      if (!b.known && (!given || !skip_below || b.cos > 0)) {
        const Vec3 wl = sc_.frame->to_local(
            equal_area_square_to_sphere({(float(x0 + x) + 0.5f) * inv_n, (float(y0 + y) + 0.5f) * inv_n}));
        b.cos = wl.z;
        if (!skip_below || wl.z > 0)
          b.f = compensate ? sc_.bsdf->eval_pdf(sc_.wo_local, wl, &b.pdf) : sc_.bsdf->eval(sc_.wo_local, wl);
      }
      double w = 0;
      if (!skip_below || b.cos > 0) {
        const double g = double((b.f * cells_->radiance(c, x, y)).average()) * std::fabs(b.cos) * inv_total;
        w = compensate ? compensated(g, double(b.pdf)) : g;
        if (!(w > 0) || !std::isfinite(w)) w = 0;
      }
      out[y * F + x] = static_cast<float>(w);
      w_sum += w;
      q_sum += double(t.importance(x0 + x, y0 + y));
    }
  const double delta = w_sum > 0 && std::isfinite(w_sum) ? kTexelMix : 1.0;
  const double a = delta < 1 ? (1 - delta) / w_sum : 0.0, b = q_sum > 0 ? delta / q_sum : 0.0;
  for (int y = 0; y < F; ++y)
    for (int x = 0; x < F; ++x)
      out[y * F + x] = static_cast<float>(a * double(out[y * F + x]) + b * double(t.importance(x0 + x, y0 + y)));
}

const DiscreteDistribution2D& OracleSampler::texels(int c, const TexelBsdf* given) const {
  int& slot = slot_[static_cast<std::size_t>(c)];
  if (slot < 0) {
    slot = static_cast<int>(built_.size());
    built_.push_back(c);
    const int F = cells_->table().cell_resolution();
    if (pool_.size() <= static_cast<std::size_t>(slot)) pool_.emplace_back(F, F);
    texel_weights(c, pool_[static_cast<std::size_t>(slot)].values(), given);
    pool_[static_cast<std::size_t>(slot)].update();
  }
  return pool_[static_cast<std::size_t>(slot)];
}

void OracleSampler::build_texels(int c, const TexelBsdf* given) const {
  if (valid_ && c >= 0 && c < top_.width() * top_.height() && top_.pmf(c) > 0) texels(c, given);
}

DirectionSample OracleSampler::sample(Point2 u) const {
  if (!valid_) return {};
  const ImportanceTable& t = cells_->table();
  const int T = t.top_resolution(), F = t.cell_resolution(), N = t.fine_resolution();
  const DiscreteDistribution2D::Sample s = top_.sample(u);
  const int c = s.y * T + s.x;
  const DiscreteDistribution2D& d = texels(c);
  if (!(s.pmf > 0) || !d.valid()) return {};
  const DiscreteDistribution2D::Sample e = d.sample(s.offset);
  const float inv_n = 1.0f / float(N);
  DirectionSample r;
  r.direction = equal_area_square_to_sphere({(float(s.x * F + e.x) + e.offset.x) * inv_n,
                                             (float(s.y * F + e.y) + e.offset.y) * inv_n});
  r.pdf = t.solid_angle_pdf(s.pmf, e.pmf * float(F) * float(F));
  r.cell = c;
  return r;
}

float OracleSampler::pdf(Vec3 wi) const {
  if (!valid_ || !is_valid_direction(wi)) return 0.0f;
  return pdf_square(equal_area_sphere_to_square(wi));
}

float OracleSampler::texel_pdf(int c, int x, int y) const {
  const float pc = valid_ ? top_.pmf(c) : 0.0f;
  if (!(pc > 0)) return 0.0f;
  const DiscreteDistribution2D& d = texels(c);
  if (!d.valid()) return 0.0f;
  const ImportanceTable& t = cells_->table();
  const int F = t.cell_resolution();
  return t.solid_angle_pdf(pc, d.pmf(x, y) * float(F) * float(F));
}

float OracleSampler::pdf_square(Point2 p) const {
  if (!valid_ || !in_unit_square(p)) return 0.0f;
  const ImportanceTable& t = cells_->table();
  const int T = t.top_resolution(), F = t.cell_resolution(), N = t.fine_resolution();
  const int c = t.cell_of(p);
  const int x = std::clamp(static_cast<int>(p.x * float(N)) - (c % T) * F, 0, F - 1);
  const int y = std::clamp(static_cast<int>(p.y * float(N)) - (c / T) * F, 0, F - 1);
  return texel_pdf(c, x, y);
}

}  // namespace envpis::render
