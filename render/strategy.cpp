#include "render/strategy.h"

#include <algorithm>
#include <chrono>
#include <cmath>


namespace envpis::render {

Strategy parse_strategy(const std::string& s) {
  for (Strategy k : all_strategies())
    if (s == to_string(k)) return k;
  throw Error("unknown strategy '" + s + "' (expected bsdf, env, mis, mis-comp, product or oracle)");
}

const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::Bsdf: return "bsdf";
    case Strategy::Env: return "env";
    case Strategy::Mis: return "mis";
    case Strategy::MisComp: return "mis-comp";
    case Strategy::Product: return "product";
    case Strategy::Oracle: return "oracle";
  }
  return "?";
}

const std::vector<Strategy>& all_strategies() {
  static const std::vector<Strategy> all{Strategy::Bsdf,    Strategy::Env,     Strategy::Mis,
                                         Strategy::MisComp, Strategy::Product, Strategy::Oracle};
  return all;
}

Heuristic parse_heuristic(const std::string& s) {
  if (s == "power") return Heuristic::Power;
  if (s == "balance") return Heuristic::Balance;
  throw Error("unknown MIS heuristic '" + s + "' (expected power or balance)");
}

const char* to_string(Heuristic h) { return h == Heuristic::Power ? "power" : "balance"; }

StrategyTables StrategyTables::build(const EnvironmentMap& env, Strategy strategy, const OracleOptions& oracle,
                                     const ProductSamplerOptions& product, const ImportanceTableOptions& light_table) {
  const auto t0 = std::chrono::steady_clock::now();
  StrategyTables t;
  t.strategy = strategy;
  t.oracle = oracle;
  t.product = product;
  if (strategy == Strategy::Oracle) {
    if (oracle.resolution < 1 || oracle.resolution > 256)
      throw Error("oracle resolution must be in 1..256, got " + std::to_string(oracle.resolution));
    const int k = static_cast<int>(std::lround(std::sqrt(double(oracle.directions))));
    if (oracle.directions < 1 || k * k != oracle.directions || k > 16)
      throw Error("oracle directions per cell must be a square number in 1..256, got " +
                  std::to_string(oracle.directions));
  }
  envpis::validate(light_table);
  t.light_table = light_table;
  t.light_table.compensated = false;
  ImportanceTableOptions opt = t.light_table;
  switch (strategy) {
    case Strategy::Bsdf: break;
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::Product: t.table = std::make_shared<ImportanceTable>(env, opt); break;
    case Strategy::MisComp:
      opt.compensated = true;
      t.table = std::make_shared<ImportanceTable>(env, opt);
      break;
    case Strategy::Oracle:
      opt.top_resolution = oracle.resolution;
      t.table = std::make_shared<ImportanceTable>(env, opt);
      break;
  }
  t.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

LightSampler::LightSampler(const StrategyTables& tables)
    : strategy_(tables.strategy), table_(tables.table.get()), oracle_(tables.oracle) {
  if (strategy_ == Strategy::Product && table_) product_ = std::make_unique<ProductSampler>(*table_, tables.product);
  if (strategy_ == Strategy::Oracle && table_) {
    const std::size_t cells = static_cast<std::size_t>(table_->cell_count());
    const std::size_t n = cells * static_cast<std::size_t>(oracle_.directions);
    su_.resize(n);
    sv_.resize(n);
    dx_.resize(n);
    dy_.resize(n);
    dz_.resize(n);
    oracle_top_ = DiscreteDistribution2D(table_->top_resolution(), table_->top_resolution());
    active_.reserve(cells);
  }
}

LightSampler::LightSampler(LightSampler&&) noexcept = default;
LightSampler::~LightSampler() = default;

void LightSampler::prepare(const ShadingContext& sc) {
  if (strategy_ == Strategy::Product) {
    if (!product_) return;
    BsdfProxy proxy;
    sc.bsdf->fill_proxy(proxy, sc.wo_local);
    if (sc.cos_bent < 1) {
      proxy.alpha_reflection = widen_roughness(proxy.alpha_reflection, sc.cos_bent);
      proxy.alpha_refraction = widen_roughness(proxy.alpha_refraction, sc.cos_bent);
    }
    product_->prepare(sc.n, sc.wo, proxy);
    return;
  }
  if (strategy_ != Strategy::Oracle || !table_) return;

  // Oracle: weight each top cell by E[c] times the average of the true f * |cos| at k x k stratified
  // directions inside it (one random offset per shading point, shared by all cells' strata).
  oracle_valid_ = false;
  const int R = table_->top_resolution();
  const int k = static_cast<int>(std::lround(std::sqrt(double(oracle_.directions))));
  const int per_cell = k * k;
  const int cells = R * R;
  // Directions below the surface carry nothing a light sample can use: for reflection-only materials
  // (f = 0 there), and for closed surfaces, whose local -Z is the inside of the object: a shadow ray
  // into it is always blocked (Material::set_closed_surface; the product proxy leaves out the same
  // lobes, so the oracle stays the limit of the method under the same knowledge).
  const bool skip_below = sc.opaque || sc.bsdf->closed_surface();
  // Cells to evaluate: positive environment importance, and (when skipping below) a cone not
  // entirely below the surface (angle(axis, n) >= 90 deg + half-angle <=> cos <= -sin(half-angle)).
  active_.clear();
  for (int c = 0; c < cells; ++c) {
    if (!(table_->cell_probability(c) > 0)) continue;
    if (skip_below) {
      const Cone& cone = table_->cell_cone(c);
      if (dot(cone.axis, sc.n) <= -cone.sin_half_angle) continue;
    }
    active_.push_back(c);
  }
  const float ox = float(sc.jitter >> 40) * 0x1p-24f;
  const float oy = float((sc.jitter >> 16) & 0xffffff) * 0x1p-24f;
  const float inv_r = 1.0f / float(R), inv_k = 1.0f / float(k);
  std::size_t i = 0;
  for (int c : active_) {
    const int cx = c % R, cy = c / R;
    for (int sy = 0; sy < k; ++sy)
      for (int sx = 0; sx < k; ++sx, ++i) {
        su_[i] = std::min((float(cx) + (float(sx) + ox) * inv_k) * inv_r, 1.0f);
        sv_[i] = std::min((float(cy) + (float(sy) + oy) * inv_k) * inv_r, 1.0f);
      }
  }
  equal_area_square_to_sphere(i, su_.data(), sv_.data(), dx_.data(), dy_.data(), dz_.data());
  float* cell_weight = oracle_top_.values();
  std::fill(cell_weight, cell_weight + cells, 0.0f);
  for (std::size_t a = 0; a < active_.size(); ++a) {
    const int c = active_[a];
    float acc = 0;
    const std::size_t base = a * static_cast<std::size_t>(per_cell);
    for (int s = 0; s < per_cell; ++s) {
      const Vec3 wi{dx_[base + s], dy_[base + s], dz_[base + s]};
      const Vec3 wl = sc.frame->to_local(wi);
      if (skip_below && !(wl.z > 0)) continue;
      const Rgb f = sc.bsdf->eval(sc.wo_local, wl);
      acc += f.average() * std::fabs(wl.z);
    }
    const float w = table_->cell_probability(c) * acc / float(per_cell);
    cell_weight[c] = w > 0 && std::isfinite(w) ? w : 0.0f;
  }
  oracle_top_.update();
  oracle_valid_ = oracle_top_.valid();
}

DirectionSample LightSampler::sample(Point2 u) const {
  switch (strategy_) {
    case Strategy::Bsdf: return {};
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp: return table_ ? table_->sample(u) : DirectionSample{};
    case Strategy::Product: return product_ ? product_->sample(u) : DirectionSample{};
    case Strategy::Oracle: return oracle_valid_ ? table_->sample(oracle_top_, u) : DirectionSample{};
  }
  return {};
}

float LightSampler::pdf(Vec3 wi) const {
  switch (strategy_) {
    case Strategy::Bsdf: return 0;
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp: return table_ ? table_->pdf(wi) : 0.0f;
    case Strategy::Product: return product_ ? product_->pdf(wi) : 0.0f;
    case Strategy::Oracle: return oracle_valid_ ? table_->pdf(oracle_top_, wi) : 0.0f;
  }
  return 0;
}

}  // namespace envpis::render
