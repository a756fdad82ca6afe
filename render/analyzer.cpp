// SPDX-License-Identifier: Apache-2.0
#include "render/analyzer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "render/analyzer_integrand.h"
#include "render/analyzer_sums.h"
#include "render/camera.h"
#include "render/hash.h"
#include "render/integrator.h"

namespace envpis::render {

using namespace analyzer_detail;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

void validate(const AnalyzerOptions& o) {
  if (o.strategies.empty()) throw Error("analyzer: no strategy given");
  if (o.refine < 1 || o.refine > 64) throw Error("analyzer: refine must be in 1..64, got " + std::to_string(o.refine));
  if (!(o.refine_share > 0 && o.refine_share <= 1))
    throw Error("analyzer: refine share must be in (0, 1], got " + std::to_string(o.refine_share));
  if (!(o.refine_tolerance > 0 && o.refine_tolerance <= 1))
    throw Error("analyzer: refine tolerance must be in (0, 1], got " + std::to_string(o.refine_tolerance));
  for (int t : o.exact_levels)
    if (t < 1 || t > 1024) throw Error("analyzer: exact level must be in 1..1024, got " + std::to_string(t));
  envpis::validate(o.light_table);
}

double geometric_mean(const std::vector<double>& values) {
  double s = 0;
  int n = 0;
  for (double v : values)
    if (v > 0 && std::isfinite(v)) {
      s += std::log(v);
      ++n;
    }
  return n > 0 ? std::exp(s / n) : kNaN;
}

std::vector<ShadingPointRef> first_hit_points(const Scene& scene, int per_object) {
  if (per_object < 1) throw Error("analyzer: points per object must be at least 1");
  const CameraSpec& spec = scene.camera();
  const Camera camera(spec, spec.width, spec.height);
  std::vector<std::vector<ShadingPointRef>> hits(scene.objects().size());
  for (int y = 0; y < spec.height; ++y)
    for (int x = 0; x < spec.width; ++x) {
      const Ray ray = camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
      SurfaceHit hit;
      if (!scene.intersect(ray, &hit) || hit.object < 0) continue;
      hits[static_cast<std::size_t>(hit.object)].push_back({hit.object, x, y, ray});
    }
  std::vector<ShadingPointRef> points;
  for (const auto& h : hits) {
    const std::size_t n = h.size(), m = std::min<std::size_t>(n, static_cast<std::size_t>(per_object));
    for (std::size_t i = 0; i < m; ++i) points.push_back(h[(2 * i + 1) * n / (2 * m)]);
  }
  return points;
}

namespace {

/// The first pass's values of the integrands refinement watches, per fine texel (0 where f is 0):
/// f_blind, f^2 / p_env and f^2 / p_bsdf (channel averages) at the texel's centre.
struct TexelGrid {
  int n = 0;
  std::vector<std::array<float, 3>> q;
  std::array<double, 3> total{};  // the sums of q's values, in row-major order
  const std::array<float, 3>& at(int x, int y) const { return q[static_cast<std::size_t>(y) * n + x]; }
};

/// The texels whose midpoint value is not good enough: those that carry more than `share` of one of
/// the watched integrals, or whose midpoint error, estimated from the second differences to their
/// four neighbours (h^2/24 (f_xx + f_yy) per unit area), exceeds `tolerance` of it.
std::vector<int> texels_to_refine(const TexelGrid& g, double share, double tolerance) {
  const std::array<double, 3>& total = g.total;
  std::vector<int> out;
  for (int y = 0; y < g.n; ++y)
    for (int x = 0; x < g.n; ++x) {
      const auto& c = g.at(x, y);
      if (!(c[0] > 0)) continue;
      std::array<float, 3> curvature{};
      for (int axis = 0; axis < 2; ++axis) {
        std::array<float, 3> side_sum{};
        for (int step : {-1, 1}) {
          int nx = x + (axis == 0 ? step : 0), ny = y + (axis == 1 ? step : 0);
          if (nx < 0 || ny < 0 || nx >= g.n || ny >= g.n)
            equal_area_wrap(g.n, nx, ny);  // the neighbour on the sphere across the square's edge
          const auto& nb = g.at(nx, ny);
          for (int k = 0; k < 3; ++k) side_sum[k] += nb[k];
        }
        for (int k = 0; k < 3; ++k) curvature[k] += std::fabs(side_sum[k] - 2 * c[k]);
      }
      bool refine = false;
      for (int k = 0; k < 3 && !refine; ++k)
        refine = c[k] > share * total[k] || curvature[k] / 24 > tolerance * total[k];
      if (refine) out.push_back(y * g.n + x);
    }
  return out;
}

constexpr int kMaxPointsPerSide = 64;  // in one texel
constexpr double kDeepTolerance = 100;

/// The points of a refined texel, kept so that they can be taken out of the sums again.
struct Kept {
  std::vector<DirectionValues> v;
  std::vector<QuadraturePoint> q;
  Batch batch() const { return {v.data(), q.data(), v.size()}; }
};

/// Evaluates the texel square `whole` on a k x k grid, adds the points to the sums (and to *kept)
/// and returns their watched integrals (see TexelGrid).
std::array<double, 3> add_square(const PointEvaluator& point, const QuadraturePoint& whole, int k, double texel_area,
                                 Kept* kept, const AnalyzerOptions& o, const std::vector<int>& distribution, Sums& s,
                                 PointAnalysis* r) {
  std::array<double, 3> watched{};
  const double size = whole.size / k, w = texel_area / (double(k) * k);
  kept->v.clear();
  kept->q.clear();
  DirectionValues v;
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const QuadraturePoint q{whole.x + i * size, whole.y + j * size, size, w};
      if (!point.eval(q.centre(), &v)) continue;
      ++r->evaluations;
      kept->v.push_back(v);
      kept->q.push_back(q);
      const double fa = v.f.average();
      watched[0] += w * v.f_blind;
      if (v.p_light[0] > 0) watched[1] += w * fa * fa / v.p_light[0];
      if (v.p_bsdf > 0) watched[2] += w * fa * fa / v.p_bsdf;
    }
  accumulate(kept->batch(), o, distribution, s);
  return watched;
}

}  // namespace

namespace {

/// Rows of texels per band of the first pass when no oracle's cells set them.
constexpr int kBandRows = 8;

/// Pass 1: the centre of every fine texel (directions, radiance and the point-independent densities
/// from the per-map TexelCentres), in bands of `band` rows. With an oracle whose cells are `band` rows
/// of the quadrature's texels (oracle >= 0), its texel distributions are built from the band's own
/// BSDF values before its density is looked up: one evaluation of the material per texel, not two.
struct FirstPass {
  const PointEvaluator& point;
  const std::vector<LightSampler>& samplers;
  const AnalyzerOptions& options;
  const std::vector<int>& distribution;
  int n, oracle, band;
  double texel_area;

  void run(PassScratch& scratch, Sums& s, PointAnalysis* r, std::array<double, 3>* total) const {
    const TexelSplits splits = texel_splits(n, options.exact_levels);
    const std::size_t un = static_cast<std::size_t>(n), size = static_cast<std::size_t>(band) * un;
    scratch.values.resize(size);
    scratch.counts.resize(size);
    scratch.texel.resize(size);
    if (oracle >= 0) scratch.bsdf.resize(size);
    for (int y0 = 0; y0 < n; y0 += band) {
      const int rows = std::min(band, n - y0);
      const std::size_t first = static_cast<std::size_t>(y0) * un;
      // Rows and columns by loop index (j = y * n + x in the band): no integer division per texel.
      for (int y = 0, j = 0; y < rows; ++y)
        for (int x = 0; x < n; ++x, ++j)
          scratch.counts[j] = point.eval_centre(x, y0 + y, &scratch.values[j], oracle >= 0 ? &scratch.bsdf[j] : nullptr);
      if (oracle >= 0) oracle_densities(scratch, y0, rows);
      std::size_t counted = 0;  // the band's counted texels, moved to its front
      for (std::size_t y = 0, j = 0; y < static_cast<std::size_t>(rows); ++y)
        for (std::size_t x = 0; x < un; ++x, ++j) {
          if (!scratch.counts[j]) {
            scratch.grid[first + j] = {};
            continue;
          }
          const DirectionValues& v = scratch.values[j];
          scratch.texel[counted] = {static_cast<int>(x), y0 + static_cast<int>(y)};
          const float fa = v.f.average();
          const std::array<float, 3> watched{v.f_blind, v.p_light[0] > 0 ? fa * fa / v.p_light[0] : 0.0f,
                                             v.p_bsdf > 0 ? fa * fa / v.p_bsdf : 0.0f};
          scratch.grid[first + j] = watched;
          for (int k = 0; k < 3; ++k) (*total)[k] += watched[k];  // the texels left at 0 add nothing
          scratch.values[counted++] = v;
        }
      r->evaluations += counted;
      accumulate(Batch{scratch.values.data(), nullptr, counted, scratch.texel.data(), &splits, texel_area}, options,
                 distribution, s);
    }
  }

  // The oracle's cells in the band (a row of them: band is their side, a divisor of n) get their texel
  // distributions from the band's BSDF values, then every counted texel its density (0 without an
  // oracle sampler: an empty table, as LightSampler::pdf_square says).
  void oracle_densities(PassScratch& scratch, int y0, int rows) const {
    const OracleSampler* o = samplers[static_cast<std::size_t>(oracle)].oracle_sampler();
    const std::size_t un = static_cast<std::size_t>(n), F = static_cast<std::size_t>(band), cells = un / F;
    const std::size_t row = static_cast<std::size_t>(y0) / F;
    scratch.cell.resize(F * F);
    for (std::size_t cx = 0; o && cx < cells; ++cx) {
      for (std::size_t y = 0; y < F; ++y)
        std::copy_n(scratch.bsdf.begin() + static_cast<std::ptrdiff_t>(y * un + cx * F), F,
                    scratch.cell.begin() + static_cast<std::ptrdiff_t>(y * F));
      o->build_texels(static_cast<int>(row * cells + cx), scratch.cell.data());
    }
    std::size_t j = 0;
    for (int y = 0; y < rows; ++y)
      for (std::size_t cx = 0; cx < cells; ++cx)
        for (int x = 0; x < band; ++x, ++j)
          if (scratch.counts[j])
            scratch.values[j].p_light[static_cast<std::size_t>(oracle)] =
                o ? o->texel_pdf(static_cast<int>(row * cells + cx), x, y) : 0.0f;
  }
};

}  // namespace

std::optional<PointAnalysis> Analyzer::analyze(const Ray& camera_ray, std::uint64_t jitter) const {
  SurfaceHit hit;
  if (!scene_.intersect(camera_ray, &hit) || hit.material < 0) return std::nullopt;
  // The thread's samplers and first-pass memory, taken out while in use: safe even if a nested
  // parallel loop ran another point on this thread.
  std::vector<LightSampler> samplers;
  samplers.swap(sampler_scratch_.local());
  std::unique_ptr<PassScratch> scratch = std::move(pass_scratch_.local());
  if (!scratch) scratch = std::make_unique<PassScratch>();
  const PointEvaluator point(scene_, hit, -camera_ray.direction, options_.visibility, tables_, *centres_, jitter,
                             samplers, shared_oracle_);
  const int n = grid_resolution();
  const double texel_area = 4.0 * kPi / (double(n) * n);
  Sums s;
  s.strategies.resize(options_.strategies.size());
  s.init_exact(options_.exact_levels);
  PointAnalysis r;

  TexelGrid grid;
  grid.n = n;
  scratch->grid.resize(static_cast<std::size_t>(n) * n);  // the first pass writes every texel
  const FirstPass pass{point, samplers, options_, distribution_, n, shared_oracle_,
                       shared_oracle_ >= 0 ? oracle_rows_ : kBandRows, texel_area};
  pass.run(*scratch, s, &r, &grid.total);
  grid.q.swap(scratch->grid);
  DirectionValues v;

  // Pass 2: the texels whose midpoint is not good enough, on a refine x refine grid each, and again
  // refine times finer while that changes the texel's watched integrals by more than
  // kDeepTolerance x refine_tolerance of their totals (a sun's edge needs 16 x 16 points per texel).
  const int m = options_.refine;
  if (m > 1) {
    std::array<double, 3> total;
    for (int k = 0; k < 3; ++k) total[k] = grid.total[k] * texel_area;
    Kept kept;
    for (int t : texels_to_refine(grid, options_.refine_share, options_.refine_tolerance)) {
      const QuadraturePoint whole{double(t % n) / n, double(t / n) / n, 1.0 / n, -texel_area};
      point.eval(whole.centre(), &v);
      accumulate(v, whole, options_, distribution_, s);
      std::array<double, 3> previous;
      for (int k = 0; k < 3; ++k) previous[k] = double(grid.q[static_cast<std::size_t>(t)][k]) * texel_area;
      for (int k = m;; k *= m) {
        const std::array<double, 3> current = add_square(point, whole, k, texel_area, &kept, options_, distribution_, s, &r);
        if (k * m > kMaxPointsPerSide) break;
        double change = 0;
        for (int q = 0; q < 3; ++q)
          if (total[q] > 0) change = std::max(change, std::fabs(current[q] - previous[q]) / total[q]);
        if (change / m <= kDeepTolerance * options_.refine_tolerance) break;
        for (QuadraturePoint& q : kept.q) q.w = -q.w;
        accumulate(kept.batch(), options_, distribution_, s);
        previous = current;
      }
    }
  }
  grid.q.swap(scratch->grid);
  pass_scratch_.local() = std::move(scratch);
  samplers.swap(sampler_scratch_.local());
  if (!finish(s, options_, distribution_, cell_mass_, &r)) return std::nullopt;
  return r;
}


Analyzer::Analyzer(const Scene& scene, const AnalyzerOptions& options, const StrategyTableSource& source)
    : scene_(scene), options_(options) {
  validate(options_);
  const auto t0 = std::chrono::steady_clock::now();
  const EnvironmentMap& env = scene.environment();
  // Its quadrature runs over the equal-area fine texels: tables with the map's own texels
  // (FineTexels::Map) are analyzed through their equal-area twins, built with the same options.
  ImportanceTableOptions equal_area = options_.light_table;
  equal_area.fine_texels = FineTexels::EqualArea;
  auto build = [&](Strategy s) {
    if (source) {
      StrategyTables t = source(s);
      if (!t.table || t.table->fine_texels() == FineTexels::EqualArea) return t;
    }
    return StrategyTables::build(env, s, options_.oracle, options_.product, equal_area, options_.product_compensation);
  };
  // Distribution 0 is the environment table (env, mis, and the limits' fine density); the product
  // shares it, as the renderer's product strategy does, unless over the compensated table.
  auto wants = [&](Strategy s) {
    return std::find(options_.strategies.begin(), options_.strategies.end(), s) != options_.strategies.end();
  };
  const bool own_product = wants(Strategy::Product) &&
                           compensation_for(options_.product_compensation, Strategy::Product) == ProductCompensation::On;
  std::vector<Strategy> built{Strategy::Mis};
  if (wants(Strategy::MisComp)) built.push_back(Strategy::MisComp);
  if (own_product) built.push_back(Strategy::Product);  // its own, compensated table
  if (wants(Strategy::Oracle)) built.push_back(Strategy::Oracle);
  tables_.resize(built.size());
  // Without a source the tables are built together (they share the map's gather); a caller's source
  // is asked in turn.
  if (source) {
    for (std::size_t i = 0; i < built.size(); ++i) tables_[i] = build(built[i]);
  } else {
    tables_ = StrategyTables::build_together(env, built, options_.oracle, options_.product, equal_area,
                                            options_.product_compensation);
  }
  if (wants(Strategy::Product) && !own_product) {
    StrategyTables t = tables_.front();
    t.strategy = Strategy::Product;
    tables_.insert(tables_.begin() + (wants(Strategy::MisComp) ? 2 : 1), std::move(t));
  }
  for (Strategy s : options_.strategies) {
    int k = -1;
    if (s != Strategy::Bsdf) {
      const Strategy key = s == Strategy::Env ? Strategy::Mis : s;  // env draws from the same table as mis
      for (std::size_t i = 0; i < tables_.size(); ++i)
        if (tables_[i].strategy == key) k = static_cast<int>(i);
    }
    distribution_.push_back(k);
  }
  const int n = grid_resolution();
  for (int t : options_.exact_levels)
    if (t > n)
      throw Error("analyzer: exact level " + std::to_string(t) + " is finer than the table's fine grid (" +
                  std::to_string(n) + ")");
  centres_ = std::make_unique<TexelCentres>(env, n, tables_);
  for (std::size_t k = 0; k < tables_.size(); ++k) {
    const ImportanceTable* t = tables_[k].table.get();
    if (tables_[k].strategy == Strategy::Oracle && t && t->fine_resolution() == n &&
        t->fine_texels() == FineTexels::EqualArea) {  // its cells' texels are the quadrature's
      shared_oracle_ = static_cast<int>(k);
      oracle_rows_ = t->cell_resolution();
    }
  }
  build_cell_masses();
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Analyzer::~Analyzer() = default;

int Analyzer::grid_resolution() const { return tables_.front().table->fine_resolution(); }

// The environment density's mass in every cell of every exact level: texels are split exactly where a
// cell boundary crosses them (the density is constant over a texel).
void Analyzer::build_cell_masses() {
  const ImportanceTable& table = *tables_.front().table;
  const int n = table.fine_resolution();
  const double area = 4.0 * kPi / (double(n) * n);
  const std::vector<float>& texel_pdf = centres_->pdf[0];  // the table's density at each texel's centre
  cell_mass_.clear();
  for (int t : options_.exact_levels) {
    std::vector<double> mass(static_cast<std::size_t>(t) * t, 0.0);
    for (int y = 0; y < n; ++y) {
      const Split sy = split(double(y) / n, 1.0 / n, t);
      for (int x = 0; x < n; ++x) {
        const Split sx = split(double(x) / n, 1.0 / n, t);
        const double m = double(texel_pdf[static_cast<std::size_t>(y) * n + x]) * area;
        for (int cy = sy.c0; cy <= sy.c1; ++cy)
          for (int cx = sx.c0; cx <= sx.c1; ++cx)
            mass[static_cast<std::size_t>(cy) * t + cx] +=
                m * (cx == sx.c0 ? sx.f0 : 1 - sx.f0) * (cy == sy.c0 ? sy.f0 : 1 - sy.f0);
      }
    }
    cell_mass_.push_back(std::move(mass));
  }
}

namespace {

/// Geometric mean over an object's points of one quantity.
template <class F>
double object_mean(const ObjectAnalysis& r, F get) {
  std::vector<double> v;
  for (const PointAnalysis& p : r.points) v.push_back(get(p));
  return geometric_mean(v);
}

void summarize(ObjectAnalysis& r, const AnalyzerOptions& o) {
  for (std::size_t i = 0; i < o.strategies.size(); ++i) {
    r.v.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v[i]; }));
    r.v_light.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v_light[i]; }));
    double sum = 0;
    for (const PointAnalysis& p : r.points) sum += p.v[i];
    r.v_mean.push_back(r.points.empty() ? kNaN : sum / double(r.points.size()));
  }
  // The geometric mean leaves zeros out; a limit of 0 at every point is 0, not undefined.
  const bool all_zero = std::all_of(r.points.begin(), r.points.end(), [](const PointAnalysis& p) { return p.v_product == 0; });
  r.v_product = all_zero && !r.points.empty() ? 0.0 : object_mean(r, [](const PointAnalysis& p) { return p.v_product; });
  for (std::size_t l = 0; l < o.exact_levels.size(); ++l)
    r.v_exact.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v_exact[l]; }));
}

template <class T>
int index_in(const std::vector<T>& list, T x) {
  const auto it = std::find(list.begin(), list.end(), x);
  return it == list.end() ? -1 : static_cast<int>(it - list.begin());
}

}  // namespace

SceneAnalysis analyze_scene(const Analyzer& analyzer, const Scene& scene, int per_object, std::uint64_t seed) {
  const auto t0 = std::chrono::steady_clock::now();
  SceneAnalysis a;
  a.per_object = per_object;
  const std::vector<ShadingPointRef> refs = first_hit_points(scene, per_object);
  std::vector<std::optional<PointAnalysis>> out(refs.size());
  tbb::parallel_for(std::size_t(0), refs.size(), [&](std::size_t i) {
    const ShadingPointRef& r = refs[i];
    out[i] = analyzer.analyze(r.ray, mix64(seed ^ mix64(std::uint64_t(r.pixel_y) * 65536 + r.pixel_x)));
  });
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (std::size_t i = 0; i < refs.size(); ++i) {  // refs are grouped by object, in id order
    if (!out[i]) {
      ++a.skipped;
      continue;
    }
    if (a.objects.empty() || a.objects.back().object != refs[i].object) a.objects.push_back({});
    ObjectAnalysis& o = a.objects.back();
    o.object = refs[i].object;
    o.refs.push_back(refs[i]);
    a.evaluations += out[i]->evaluations;
    o.points.push_back(std::move(*out[i]));
    ++a.analyzed;
  }
  for (ObjectAnalysis& o : a.objects) summarize(o, analyzer.options());
  return a;
}

Decomposition decompose(const ObjectAnalysis& r, const AnalyzerOptions& o) {
  const int env = index_in(o.strategies, Strategy::Env), product = index_in(o.strategies, Strategy::Product),
            mis = index_in(o.strategies, Strategy::Mis);
  const int lo = index_in(o.exact_levels, 12), hi = index_in(o.exact_levels, 48);
  auto at = [](const std::vector<double>& v, int i) { return i >= 0 ? v[static_cast<std::size_t>(i)] : kNaN; };
  Decomposition d;
  d.env_over_product = at(r.v_light, env) / at(r.v_light, product);
  d.product_over_exact12 = at(r.v_light, product) / at(r.v_exact, lo);
  d.exact12_over_exact48 = at(r.v_exact, lo) / at(r.v_exact, hi);
  d.mis_over_product = at(r.v, mis) / at(r.v, product);
  return d;
}

}  // namespace envpis::render
