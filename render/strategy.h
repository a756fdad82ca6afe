// SPDX-License-Identifier: Apache-2.0
// The light-sampling strategies compared by the renderer. Each is a pair of
// (light distribution, whether BSDF sampling is combined with it by MIS):
//
//   bsdf      BSDF sampling only; no light sample.
//   env       light samples from the environment's ImportanceTable only; BSDF-sampled directions
//             carry no environment radiance (in the path integrator they only continue the path).
//   mis       ImportanceTable + BSDF sampling, MIS (the paper's baseline).
//   mis-comp  a compensated ImportanceTable (Karlik et al. 2019: max(0, importance - mean)) + BSDF
//             sampling, MIS (pbrt-v4's default: a stronger baseline).
//   product   the library's ProductSampler (environment x BSDF proxy) + BSDF sampling, MIS.
//   oracle    a per-shading-point top level over the cells of a finer table (48 x 48 by default)
//             weighted by each cell's estimated true share of BSDF * |cos| * radiance, then the
//             cell's fine texels weighted by the same product; + BSDF sampling, MIS
//             (render/oracle.h). Slow: the limit the paper's two-level method approaches.
//
// Portal-aware variants (issue 24; docs/portals.md, "In the renderer"), for scenes with portals
// (Scene::portals): env-portal, mis-portal, mis-comp-portal and product-portal use the same table as
// env, mis, mis-comp and product, but per shading point a PortalView prepared at the hit point masks
// it: PortalEnvironmentSampler for the first three, ProductSampler::prepare(n, wo, proxy, &view) for
// product-portal (with the product cache, a camera ray's hits share it when their key, with the point p
// rounded, is the same: envpis/product_cache.h; deeper vertices, or without the cache, exactly per point). Where the view sees no portal (or the masked
// distribution is empty) the point has no light sample and pdf() is 0, so BSDF samples carry it alone
// (MIS weight 1): unbiased for the MIS variants even when portals miss part of an opening.
// env-portal has no BSDF hits, so it is unbiased only when the portals cover every opening.
// They are separate names (not a switch) so `compare` can set both variants side by side; they are
// not in all_strategies() (a scene without portals has nothing for them: render() rejects that).
//
// Tables (StrategyTables) are built once per environment and strategy and shared by all threads;
// a LightSampler (one per thread) turns them into a distribution per shading point.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "envpis/envpis.h"
#include "render/material.h"
#include "render/math.h"

namespace envpis::render {

enum class Strategy { Bsdf, Env, Mis, MisComp, Product, Oracle, EnvPortal, MisPortal, MisCompPortal, ProductPortal };
/// "bsdf" | "env" | "mis" | "mis-comp" | "product" | "oracle", or one of the portal variants
/// "env-portal" | "mis-portal" | "mis-comp-portal" | "product-portal"; throws Error otherwise.
Strategy parse_strategy(const std::string& s);
const char* to_string(Strategy s);
/// The strategies without portals (every scene can use them).
const std::vector<Strategy>& all_strategies();
/// The portal-aware variants (scenes with portals only).
const std::vector<Strategy>& portal_strategies();
/// Whether s is a portal-aware variant.
bool uses_portals(Strategy s);
/// The strategy without portals a variant masks (s itself for the others): its table and options.
Strategy base_strategy(Strategy s);

enum class Heuristic { Power, Balance };
Heuristic parse_heuristic(const std::string& s);  ///< "power" | "balance"
const char* to_string(Heuristic h);

/// product: which of its light distributions take the MIS-compensated table (max(0, importance -
/// mean), as mis-comp's; Karlik et al. 2019), leaving directions below the map's mean to the BSDF
/// sample, which MIS then weighs fully. Off: none (the paper's). Elsewhere: the vertices that do not
/// use the product (StrategyTables::product_max_roughness, product_depth) sample mis-comp's table
/// instead of mis's. Deeper: those and the product's environment factor at the vertices after a
/// camera ray's hit (depth >= 1); the camera ray's hit keeps the plain product. On: the product's
/// environment factor at every vertex too. product-portal: its masked environment and its product
/// share one table, so only On changes it (both compensated). OnWithoutPortals: On for product,
/// Off for product-portal, which lost with the compensated table in the two-window room along paths
/// (docs/assets.md, "`auto`").
enum class ProductCompensation { Off, Elsewhere, Deeper, On, OnWithoutPortals };
/// "off" | "elsewhere" | "deeper" | "on" | "on-without-portals"
ProductCompensation parse_product_compensation(const std::string& s);
const char* to_string(ProductCompensation c);
/// Every value's name for an error message, "off, elsewhere, ... or on-without-portals"; with `last`
/// (a front end's own value, such as "auto") every name, then "or last".
std::string product_compensation_names(const std::string& last = "");
/// The compensation to build a render's tables with: Elsewhere and Deeper build a second table for the
/// vertices after a camera ray's hit and the vertices without the product, and with the product cache
/// (cache_entries > 0) every camera ray's hit takes the plain product, so a render without deeper
/// vertices (the direct integrator) would never sample that table: Off then, the same images without
/// its build. Anything else is returned as it is.
ProductCompensation tables_compensation(ProductCompensation c, bool deeper_vertices, int cache_entries);
/// What `c` means for strategy s: Off for the strategies without a product, OnWithoutPortals as On or
/// Off (product, product-portal), anything else as it is.
ProductCompensation compensation_for(ProductCompensation c, Strategy s);

/// The oracle's cost per shading point is about bsdf_samples + directions * (usable cells) + 16 per
/// cell on the horizon + refine_points evaluations of the BSDF and its pdf (render/oracle.h).
struct OracleOptions {
  int resolution = 48;        ///< top-level cells per side of the oracle's table (1..256)
  int directions = 4;         ///< first-pass points per cell: a square number (1, 4, 9, ..., 256)
  int bsdf_samples = 256;     ///< BSDF samples per shading point that find the lobe: a square number (0..65536)
  int refine_points = 1024;   ///< second-pass points, shared by the cells by their first estimate (0..1e6)
  /// Weight the cells for MIS with the BSDF sample (what the renderer does) rather than by their share
  /// of the integrand alone (the analyzer's exact-T limit; the better light sample without MIS).
  bool mis_compensation = true;
};

class OracleCells;
class OracleSampler;

/// What a strategy needs that is built once per environment map and shared by all threads.
struct StrategyTables {
  Strategy strategy = Strategy::Mis;
  /// The table light samples come from (null for `bsdf`): the standard table for env and mis, the
  /// compensated one for mis-comp, for product the one `product_compensation` names, the oracle's
  /// finer table for oracle.
  std::shared_ptr<const ImportanceTable> table;
  OracleOptions oracle;
  /// The oracle's per-cell radiance distributions (null for the other strategies).
  std::shared_ptr<const OracleCells> oracle_cells;
  ProductSamplerOptions product;
  /// product: which distributions are compensated (see ProductCompensation); `table` is the
  /// product's (a camera ray's hit's, with Deeper), `elsewhere_table` the one the vertices without
  /// the product sample, and with Deeper also the product's at the deeper vertices (null: `table`).
  ProductCompensation product_compensation = ProductCompensation::Off;
  std::shared_ptr<const ImportanceTable> elsewhere_table;
  /// product: share prepared distributions between shading points of one key (envpis/product_cache.h),
  /// at the first hits (a camera ray's, which repeat within a pixel); deeper vertices, whose keys almost
  /// never repeat, are prepared exactly; entries 0: prepare each shading point exactly.
  ProductCacheOptions product_cache;
  /// product: the product distribution at path vertices of depth < product_depth (0: at every vertex),
  /// the environment table's (as mis) deeper. A function of the vertex, so its MIS weights are exact.
  int product_depth = 0;
  /// product-portal with the product cache: the shading point is rounded to multiples of this
  /// fraction of the smallest portal's longer diagonal (ProductCacheOptions::position_step; the
  /// portal's spherical polygon then moves by less than this fraction of its own angular size).
  float product_cache_step = 1.0f / 32.0f;
  /// product: the product distribution only at vertices with a glossy lobe, the table's (as mis)
  /// elsewhere: where the vertex's proxy has a reflection or refraction lobe of GGX alpha (widened
  /// for a bent normal, as product uses it) at most product_max_roughness. Diffuse-only vertices and
  /// rough lobes get the table: there product's set-up costs more than its density gains
  /// (docs/assets.md, "Product where it pays"). With the product cache, a camera ray's hit (depth 0)
  /// gets the product whatever its lobe: the pixel's samples share its set-up there. A function of
  /// the vertex, so its MIS weights are exact. Infinity: at every vertex (diffuse ones too).
  float product_max_roughness = kInfinity;
  double build_seconds = 0;

  /// The options of the light table of env, mis, mis-comp and product (the oracle's table takes its
  /// peak ratio and fine resolution, and oracle.resolution as its top level; mis-comp sets compensated).
  ImportanceTableOptions light_table;

  /// Throws Error for invalid options (top resolutions 1..256, see ImportanceTable for the rest).
  static StrategyTables build(const EnvironmentMap& env, Strategy strategy, const OracleOptions& oracle = {},
                              const ProductSamplerOptions& product = {},
                              const ImportanceTableOptions& light_table = {},
                              ProductCompensation product_compensation = ProductCompensation::Off);
  /// build() for several strategies of one map at once: their tables are built together
  /// (ImportanceTable::build_together: tables on one fine grid share the map's gather). Each is the
  /// StrategyTables build() gives, its build_seconds the whole call's.
  static std::vector<StrategyTables> build_together(const EnvironmentMap& env, const std::vector<Strategy>& strategies,
                                                    const OracleOptions& oracle = {},
                                                    const ProductSamplerOptions& product = {},
                                                    const ImportanceTableOptions& light_table = {},
                                                    ProductCompensation product_compensation = ProductCompensation::Off);
};

/// The shading point a light sampler prepares for.
struct ShadingContext {
  Vec3 p;         ///< world hit point (the portal variants prepare their PortalView there)
  Vec3 n;         ///< world shading normal (the local frame's +Z)
  Vec3 wo;        ///< world outgoing direction (towards the viewer), unit
  Vec3 wo_local;  ///< the same in the local frame
  const Frame* frame = nullptr;
  const Material* bsdf = nullptr;
  std::uint64_t jitter = 0;  ///< random bits for strategies that randomize their set-up (oracle)
  /// True when the material reflects only (f = 0 below the surface): the oracle then skips the cells
  /// whose cone lies entirely below the surface and counts nothing from below in its cell weights.
  bool opaque = false;
  int depth = 0;  ///< the path vertex: 0 at the camera ray's hit
  /// Cosine between a normal-mapped shading normal and the geometric normal; below 1 the product
  /// strategy widens its proxy's roughness by that angle (envpis::widen_roughness): its proxy lobes
  /// are built about the bent normal, which the geometry's horizon does not follow. 1: not bent.
  float cos_bent = 1;
};

/// The product cache's position step through `portals`: `fraction` of the smallest one's longer diagonal.
float portal_position_step(const Portals& portals, float fraction);

/// Per-thread light sampling for one strategy. Not thread-safe; create one per thread.
class LightSampler {
 public:
  /// `portals`: the scene's, for the portal variants (copied into the per-thread view); throws Error
  /// when a portal variant gets none.
  explicit LightSampler(const StrategyTables& tables, const Portals* portals = nullptr);
  LightSampler(LightSampler&&) noexcept;
  ~LightSampler();

  Strategy strategy() const { return strategy_; }
  /// Whether this strategy draws light samples at all.
  bool has_light_samples() const { return strategy_ != Strategy::Bsdf && table_ != nullptr && !table_->empty(); }
  /// Whether BSDF-sampled directions that reach the environment contribute (with MIS weights).
  bool bsdf_hits_count() const { return base_strategy(strategy_) != Strategy::Env; }
  /// Whether the light and BSDF estimates are combined by MIS (otherwise each has weight 1).
  bool uses_mis() const { return strategy_ != Strategy::Bsdf && base_strategy(strategy_) != Strategy::Env; }

  /// Builds the per-shading-point distribution (product, oracle and the portal variants); cheap no-op
  /// for the others.
  void prepare(const ShadingContext& sc);
  /// A world direction and its solid-angle density (pdf 0: no sample).
  DirectionSample sample(Point2 u) const;
  /// Density of sample() at world direction wi.
  float pdf(Vec3 wi) const;
  /// The same, given wi's texture coordinate in the environment map the tables were built from
  /// (EnvironmentMap::texture_coord): the table's pdf then does not look wi up again.
  float pdf(Vec3 wi, Point2 texture) const;
  /// Starts fetching what pdf(wi, texture) will read (after prepare(); a hint, no result changes).
  void prefetch_pdf(Point2 texture) const;
  /// pdf() at the direction of equal-area point p, given p (ImportanceTable::pdf_square): for a
  /// quadrature over the square's texels.
  float pdf_square(Point2 p) const;
  /// pdf_square() at the centre of texel (x, y) of an n x n grid over the equal-area square; where the
  /// strategy's table has that grid, without locating the point (ImportanceTable::pdf_texel).
  float pdf_texel(int x, int y, int n) const;

  /// Product sampler (strategy product), for tests and diagnostics.
  const ProductSampler* product_sampler() const { return product_; }
  /// Oracle sampler (strategy oracle): the analyzer builds its texel distributions from its own BSDF values.
  const OracleSampler* oracle_sampler() const { return oracle_.get(); }
  /// With a product cache, the shading points that reused a prepared distribution and those that
  /// did not (the cache's misses and the deeper vertices, prepared exactly); 0 without a cache.
  std::uint64_t product_cache_hits() const;
  std::uint64_t product_cache_misses() const;

 private:
  Strategy strategy_;
  const ImportanceTable* table_ = nullptr;
  const ImportanceTable* elsewhere_ = nullptr;     // product: the vertices without the product
  std::unique_ptr<ProductSampler> product_exact_;  // without a cache, and at deeper vertices
  std::unique_ptr<ProductSampler> product_deeper_;  // ProductCompensation::Deeper: the deeper vertices'
  std::unique_ptr<ProductCache> product_first_;    // with one: a camera ray's hits
  std::uint64_t exact_points_ = 0;                 // with a cache: the points prepared exactly
  const ProductSampler* product_ = nullptr;                      // the current shading point's
  int product_depth_ = 0;
  float product_max_roughness_ = kInfinity;
  /// Whether the product distribution is used at this vertex (proxy: the vertex's, as product sees it).
  bool product_at(const ShadingContext& sc, const BsdfProxy& proxy) const;
  std::unique_ptr<OracleSampler> oracle_;
  // The portal variants: the view at the current point, the masked environment (also product-portal's
  // beyond product_depth), whether the current point has a light sample.
  std::unique_ptr<PortalView> view_;
  std::unique_ptr<PortalEnvironmentSampler> portal_env_;
  bool portal_valid_ = false;
  void prepare_portals(const ShadingContext& sc);
};

}  // namespace envpis::render
