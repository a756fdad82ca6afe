// SPDX-License-Identifier: Apache-2.0
#include "render/strategy.h"

#include "render/oracle.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>


namespace envpis::render {

Strategy parse_strategy(const std::string& s) {
  for (const auto* list : {&all_strategies(), &portal_strategies()})
    for (Strategy k : *list)
      if (s == to_string(k)) return k;
  throw Error("unknown strategy '" + s +
              "' (expected bsdf, env, mis, mis-comp, product, oracle, env-portal, mis-portal, mis-comp-portal or "
              "product-portal)");
}

const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::Bsdf: return "bsdf";
    case Strategy::Env: return "env";
    case Strategy::Mis: return "mis";
    case Strategy::MisComp: return "mis-comp";
    case Strategy::Product: return "product";
    case Strategy::Oracle: return "oracle";
    case Strategy::EnvPortal: return "env-portal";
    case Strategy::MisPortal: return "mis-portal";
    case Strategy::MisCompPortal: return "mis-comp-portal";
    case Strategy::ProductPortal: return "product-portal";
  }
  return "?";
}

const std::vector<Strategy>& portal_strategies() {
  static const std::vector<Strategy> all{Strategy::EnvPortal, Strategy::MisPortal, Strategy::MisCompPortal,
                                         Strategy::ProductPortal};
  return all;
}

bool uses_portals(Strategy s) { return base_strategy(s) != s; }

Strategy base_strategy(Strategy s) {
  switch (s) {
    case Strategy::EnvPortal: return Strategy::Env;
    case Strategy::MisPortal: return Strategy::Mis;
    case Strategy::MisCompPortal: return Strategy::MisComp;
    case Strategy::ProductPortal: return Strategy::Product;
    default: return s;
  }
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

namespace {
constexpr ProductCompensation kCompensations[] = {ProductCompensation::Off, ProductCompensation::Elsewhere,
                                                  ProductCompensation::Deeper, ProductCompensation::On,
                                                  ProductCompensation::OnWithoutPortals};
}  // namespace

std::string product_compensation_names(const std::string& last) {
  std::string list;
  for (ProductCompensation c : kCompensations) list += std::string(list.empty() ? "" : ", ") + to_string(c);
  if (last.empty()) {
    const std::size_t comma = list.rfind(", ");
    return list.substr(0, comma) + " or " + list.substr(comma + 2);
  }
  return list + " or " + last;
}

ProductCompensation parse_product_compensation(const std::string& s) {
  for (ProductCompensation c : kCompensations)
    if (s == to_string(c)) return c;
  throw Error("unknown product compensation '" + s + "' (expected " + product_compensation_names() + ")");
}

const char* to_string(ProductCompensation c) {
  switch (c) {
    case ProductCompensation::Off: return "off";
    case ProductCompensation::Elsewhere: return "elsewhere";
    case ProductCompensation::Deeper: return "deeper";
    case ProductCompensation::On: return "on";
    case ProductCompensation::OnWithoutPortals: return "on-without-portals";
  }
  return "off";
}

namespace {
// Elsewhere and Deeper sample a compensated table besides the product's plain one.
bool second_table(ProductCompensation c) {
  return c == ProductCompensation::Elsewhere || c == ProductCompensation::Deeper;
}
}  // namespace

ProductCompensation tables_compensation(ProductCompensation c, bool deeper_vertices, int cache_entries) {
  return second_table(c) && !deeper_vertices && cache_entries > 0 ? ProductCompensation::Off : c;
}

ProductCompensation compensation_for(ProductCompensation c, Strategy s) {
  if (base_strategy(s) != Strategy::Product) return ProductCompensation::Off;
  if (c == ProductCompensation::OnWithoutPortals) return uses_portals(s) ? ProductCompensation::Off : ProductCompensation::On;
  return c;
}

namespace {
// A strategy's tables before they are built: its options, checked, and the options of its table and
// of product's second table (none: top_resolution 0).
struct TablePlan {
  StrategyTables t;
  ImportanceTableOptions table, elsewhere;
};

TablePlan plan_tables(Strategy strategy, const OracleOptions& oracle, const ProductSamplerOptions& product,
                      const ImportanceTableOptions& light_table, ProductCompensation product_compensation) {
  TablePlan p;
  p.table.top_resolution = p.elsewhere.top_resolution = 0;
  StrategyTables& t = p.t;
  t.strategy = strategy;
  t.oracle = oracle;
  t.product = product;
  t.product_compensation = compensation_for(product_compensation, strategy);
  if (strategy == Strategy::Oracle) {
    if (oracle.resolution < 1 || oracle.resolution > 256)
      throw Error("oracle resolution must be in 1..256, got " + std::to_string(oracle.resolution));
    const int k = static_cast<int>(std::lround(std::sqrt(double(oracle.directions))));
    if (oracle.directions < 1 || k * k != oracle.directions || k > 16)
      throw Error("oracle directions per cell must be a square number in 1..256, got " +
                  std::to_string(oracle.directions));
    const int m = static_cast<int>(std::lround(std::sqrt(double(oracle.bsdf_samples))));
    if (oracle.bsdf_samples < 0 || m * m != oracle.bsdf_samples || m > 256)
      throw Error("oracle BSDF samples must be a square number in 0..65536, got " +
                  std::to_string(oracle.bsdf_samples));
    if (oracle.refine_points < 0 || oracle.refine_points > 1000000)
      throw Error("oracle refine points must be in 0..1000000, got " + std::to_string(oracle.refine_points));
  }
  envpis::validate(light_table);
  t.light_table = light_table;
  t.light_table.compensated = false;
  ImportanceTableOptions opt = t.light_table;
  switch (base_strategy(strategy)) {  // a portal variant masks its base strategy's table per point
    case Strategy::Bsdf: break;
    case Strategy::Env:
    case Strategy::Mis: p.table = opt; break;
    case Strategy::Product:
      opt.compensated = t.product_compensation == ProductCompensation::On;
      p.table = opt;
      // product-portal samples its masked `table` at the other vertices: no second table for it.
      if (second_table(t.product_compensation) && !uses_portals(strategy)) {
        opt.compensated = true;
        p.elsewhere = opt;
      }
      break;
    case Strategy::MisComp:
      opt.compensated = true;
      p.table = opt;
      break;
    case Strategy::Oracle:
      opt.top_resolution = oracle.resolution;
      opt.subdivision = 1;  // the oracle weighs its own finer cells; sub-cells would only cost cones
      opt.fine_texels = FineTexels::EqualArea;  // it weighs the equal-area fine texels (render/oracle.h)
      p.table = opt;
      break;
    default: break;  // base_strategy() is never a portal variant
  }
  return p;
}
}  // namespace

StrategyTables StrategyTables::build(const EnvironmentMap& env, Strategy strategy, const OracleOptions& oracle,
                                     const ProductSamplerOptions& product, const ImportanceTableOptions& light_table,
                                     ProductCompensation product_compensation) {
  return build_together(env, {strategy}, oracle, product, light_table, product_compensation).front();
}

std::vector<StrategyTables> StrategyTables::build_together(const EnvironmentMap& env,
                                                           const std::vector<Strategy>& strategies,
                                                           const OracleOptions& oracle,
                                                           const ProductSamplerOptions& product,
                                                           const ImportanceTableOptions& light_table,
                                                           ProductCompensation product_compensation) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<TablePlan> plans;
  std::vector<ImportanceTableOptions> options;  // every table of every strategy, in turn
  for (Strategy s : strategies) {
    plans.push_back(plan_tables(s, oracle, product, light_table, product_compensation));
    for (const ImportanceTableOptions* o : {&plans.back().table, &plans.back().elsewhere})
      if (o->top_resolution > 0) options.push_back(*o);
  }
  const std::vector<std::shared_ptr<const ImportanceTable>> tables = ImportanceTable::build_together(env, options);
  std::vector<StrategyTables> out;
  std::size_t next = 0;
  for (TablePlan& p : plans) {
    StrategyTables& t = p.t;
    if (p.table.top_resolution > 0) t.table = tables[next++];
    if (p.elsewhere.top_resolution > 0) t.elsewhere_table = tables[next++];
    if (t.strategy == Strategy::Oracle && !t.table->empty()) t.oracle_cells = std::make_shared<OracleCells>(env, t.table);
    out.push_back(std::move(t));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (StrategyTables& t : out) t.build_seconds = seconds;
  return out;
}

LightSampler::LightSampler(const StrategyTables& tables, const Portals* portals)
    : strategy_(tables.strategy),
      table_(tables.table.get()),
      elsewhere_(tables.elsewhere_table ? tables.elsewhere_table.get() : tables.table.get()) {
  if (uses_portals(strategy_)) {
    if (!portals || portals->empty())
      throw Error(std::string("strategy ") + to_string(strategy_) + " needs a scene with portals");
    if (table_ && !table_->empty()) {
      view_ = std::make_unique<PortalView>(*table_, *portals);
      portal_env_ = std::make_unique<PortalEnvironmentSampler>(*table_);
      if (strategy_ == Strategy::ProductPortal) {
        product_depth_ = tables.product_depth;
        product_max_roughness_ = tables.product_max_roughness;
        // With the cache, a camera ray's hits share a key (the point rounded: envpis/product_cache.h);
        // deeper vertices are prepared exactly: their keys (p and wo) almost never repeat, and a
        // cache there only adds its misses (docs/portals.md, "The product cache through portals").
        if (tables.product_cache.entries > 0) {
          ProductCacheOptions cache = tables.product_cache;
          cache.position_step = portal_position_step(*portals, tables.product_cache_step);
          product_first_ = std::make_unique<ProductCache>(*table_, *portals, tables.product, cache);
        }
        product_exact_ = std::make_unique<ProductSampler>(*table_, tables.product);
      }
    }
    return;
  }
  if (strategy_ == Strategy::Product && table_) {
    product_depth_ = tables.product_depth;
    product_max_roughness_ = tables.product_max_roughness;
    // With the cache, a camera ray's hits share a key (a pixel's samples repeat its normal and view);
    // deeper vertices are prepared exactly: their keys almost never repeat (under 0.1% on the asset
    // scenes), so a cache there would only add its look-up (docs/assets.md, "The cache at deeper vertices").
    if (tables.product_cache.entries > 0)
      product_first_ = std::make_unique<ProductCache>(*table_, tables.product, tables.product_cache);
    product_exact_ = std::make_unique<ProductSampler>(*table_, tables.product);
    if (tables.product_compensation == ProductCompensation::Deeper && tables.elsewhere_table)
      product_deeper_ = std::make_unique<ProductSampler>(*tables.elsewhere_table, tables.product);
  }
  if (strategy_ == Strategy::Oracle && tables.oracle_cells)
    oracle_ = std::make_unique<OracleSampler>(tables.oracle_cells, tables.oracle);
}

LightSampler::LightSampler(LightSampler&&) noexcept = default;
LightSampler::~LightSampler() = default;

namespace {

BsdfProxy make_proxy(const ShadingContext& sc) {
  BsdfProxy proxy;
  sc.bsdf->fill_proxy(proxy, sc.wo_local);
  if (sc.cos_bent < 1) {
    proxy.alpha_reflection = widen_roughness(proxy.alpha_reflection, sc.cos_bent);
    proxy.alpha_refraction = widen_roughness(proxy.alpha_refraction, sc.cos_bent);
  }
  return proxy;
}

}  // namespace

bool LightSampler::product_at(const ShadingContext& sc, const BsdfProxy& proxy) const {
  if (product_depth_ > 0 && sc.depth >= product_depth_) return false;
  if (!(product_max_roughness_ < kInfinity)) return true;
  // A camera ray's hits repeat within a pixel, so with the cache their set-up is mostly shared: there
  // the product pays also on rough and diffuse lobes (docs/assets.md, "The rule at the first hit").
  // Not through portals: there a diffuse hit's alternative is mis-portal's masked environment, which
  // the product did not beat (docs/portals.md, "The product cache through portals").
  if (sc.depth == 0 && product_first_ && strategy_ == Strategy::Product) return true;
  return (proxy.reflection > 0 && proxy.alpha_reflection <= product_max_roughness_) ||
         (proxy.refraction > 0 && proxy.alpha_refraction <= product_max_roughness_);
}

float portal_position_step(const Portals& portals, float fraction) {
  float smallest = kInfinity;
  for (int i = 0; i < portals.size(); ++i) {
    const Quad& q = portals.quad(i);
    smallest = std::min(smallest, std::max(length(q.v[2] - q.v[0]), length(q.v[3] - q.v[1])));
  }
  return smallest * fraction;
}

void LightSampler::prepare_portals(const ShadingContext& sc) {
  product_ = nullptr;
  portal_valid_ = false;
  const bool product = strategy_ == Strategy::ProductPortal;
  const BsdfProxy proxy = product ? make_proxy(sc) : BsdfProxy{};
  if (product && product_first_ && sc.depth == 0 && product_at(sc, proxy)) {  // its slots have their own views
    const ProductSampler& s = product_first_->prepare(sc.p, sc.n, sc.wo, proxy);
    portal_valid_ = s.valid();
    if (portal_valid_) product_ = &s;
    return;
  }
  if (!view_ || !view_->prepare(sc.p)) return;  // no portal seen from p: BSDF samples alone
  if (product && product_at(sc, proxy)) {
    portal_valid_ = product_exact_->prepare(sc.n, sc.wo, proxy, view_.get());
    if (portal_valid_) product_ = product_exact_.get();
  } else {
    portal_valid_ = portal_env_->prepare(*view_);
  }
}

void LightSampler::prepare(const ShadingContext& sc) {
  if (uses_portals(strategy_)) {
    prepare_portals(sc);
    return;
  }
  if (strategy_ == Strategy::Product) {
    product_ = nullptr;
    if (!product_exact_) return;
    const BsdfProxy proxy = make_proxy(sc);
    if (!product_at(sc, proxy)) return;  // the table's distribution (elsewhere_), as mis or mis-comp
    if (product_first_ && sc.depth == 0) {
      product_ = &product_first_->prepare(sc.n, sc.wo, proxy);
    } else {
      ProductSampler& exact = product_deeper_ && sc.depth > 0 ? *product_deeper_ : *product_exact_;
      exact.prepare(sc.n, sc.wo, proxy);
      product_ = &exact;
      ++exact_points_;
    }
    return;
  }
  if (oracle_) oracle_->prepare(sc);
}

std::uint64_t LightSampler::product_cache_hits() const {
  return product_first_ ? product_first_->hits() : 0;
}

std::uint64_t LightSampler::product_cache_misses() const {
  return product_first_ ? product_first_->misses() + exact_points_ : 0;
}

DirectionSample LightSampler::sample(Point2 u) const {
  switch (strategy_) {
    case Strategy::Bsdf: return {};
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp: return table_ ? table_->sample(u) : DirectionSample{};
    case Strategy::Product: return product_ ? product_->sample(u) : elsewhere_ ? elsewhere_->sample(u) : DirectionSample{};
    case Strategy::Oracle: return oracle_ ? oracle_->sample(u) : DirectionSample{};
    case Strategy::EnvPortal:
    case Strategy::MisPortal:
    case Strategy::MisCompPortal:
    case Strategy::ProductPortal:
      if (!portal_valid_) return {};
      return product_ ? product_->sample(u) : portal_env_->sample(u);
  }
  return {};
}

float LightSampler::pdf(Vec3 wi) const {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  return pdf(wi, Point2{kNaN, kNaN});
}

float LightSampler::pdf(Vec3 wi, Point2 texture) const {
  switch (strategy_) {
    case Strategy::Bsdf: return 0;
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp: return table_ ? table_->pdf(wi, texture) : 0.0f;
    case Strategy::Product:
      return product_ ? product_->pdf(wi, texture) : elsewhere_ ? elsewhere_->pdf(wi, texture) : 0.0f;
    case Strategy::Oracle: return oracle_ ? oracle_->pdf(wi) : 0.0f;
    case Strategy::EnvPortal:
    case Strategy::MisPortal:
    case Strategy::MisCompPortal:
    case Strategy::ProductPortal:
      // The density sample() draws from at this point (0 where it has none): the BSDF sample's MIS
      // weight then is 1, which keeps the estimate unbiased.
      if (!portal_valid_) return 0.0f;
      return product_ ? product_->pdf(wi) : portal_env_->pdf(wi);
  }
  return 0;
}

void LightSampler::prefetch_pdf(Point2 texture) const {
  switch (strategy_) {
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp:
      if (table_) table_->prefetch(texture);
      break;
    case Strategy::Product:
      if (product_) product_->table().prefetch(texture);
      else if (elsewhere_) elsewhere_->prefetch(texture);
      break;
    default: break;  // the oracle's and the portal strategies' densities read other memory
  }
}

float LightSampler::pdf_texel(int x, int y, int n) const {
  auto on_grid = [n](const ImportanceTable* t) {
    return t && t->fine_texels() == FineTexels::EqualArea && t->fine_resolution() == n;
  };
  switch (strategy_) {
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp:
      if (on_grid(table_)) return table_->pdf_texel(x, y);
      break;
    case Strategy::Product:
      if (product_ && on_grid(&product_->table())) return product_->pdf_texel(x, y);
      if (!product_ && on_grid(elsewhere_)) return elsewhere_->pdf_texel(x, y);
      break;
    default: break;
  }
  return pdf_square(texel_centre(x, y, n));
}

float LightSampler::pdf_square(Point2 p) const {
  switch (strategy_) {
    case Strategy::Bsdf: return 0;
    case Strategy::Env:
    case Strategy::Mis:
    case Strategy::MisComp: return table_ ? table_->pdf_square(p) : 0.0f;
    case Strategy::Product: return product_ ? product_->pdf_square(p) : elsewhere_ ? elsewhere_->pdf_square(p) : 0.0f;
    case Strategy::Oracle: return oracle_ ? oracle_->pdf_square(p) : 0.0f;
    case Strategy::EnvPortal:
    case Strategy::MisPortal:
    case Strategy::MisCompPortal:
    case Strategy::ProductPortal: return pdf(equal_area_square_to_sphere(p));
  }
  return 0;
}

}  // namespace envpis::render
