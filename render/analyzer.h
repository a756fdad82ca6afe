// SPDX-License-Identifier: Apache-2.0
// The exact variance analyzer: the variance of the direct integrator's one-sample estimate at a shading
// point, for each strategy, computed by quadrature instead of by rendering (no Monte Carlo noise).
//
// At a shading point the direct integrator (render/integrator.h) draws one light sample x_l ~ p_l and
// one BSDF sample x_b ~ p_b, independently, and returns
//     F = w_l(x_l) f(x_l) / p_l(x_l) + w_b(x_b) f(x_b) / p_b(x_b),
// with f = BSDF * |cos| * environment radiance (* visibility) and the strategy's weights (the MIS
// heuristic's for mis, mis-comp, product and oracle; w_b = 0 for env; no light sample for bsdf).
// Since the two samples are independent, per RGB channel
//     Var F = sum over t in {l, b} of [ integral w_t^2 f^2 / p_t  -  (integral w_t f)^2 ],
// and the analyzer reports V = Var F / I^2 averaged over the channels with I > 0 (I = integral f):
// the relative variance of one sample, what `envpis compare`'s relMSE (the channel mean of
// (I - R)^2 / R^2 per pixel) measures at one shading point, up to its 0.01 offset.
//
// Besides the renderer's estimator ("v"), each light distribution is also scored alone ("v_light":
// the light sample with weight 1, no BSDF sample: the chi-square divergence of p_l from f), and two
// kinds of limits that no light distribution knowing the BSDF and the environment but not visibility
// can beat:
//   product   sampling proportional to the channel average of f without visibility, exactly
//             (V is then 0 for a grey integrand; for RGB it is what the channels' differing
//             shapes cost, usually tiny);
//   exact-T   a top cell of a T x T grid over the equal-area square chosen with probability equal
//             to its exact share of that integrand, then a direction inside it from the
//             environment table's own density restricted to the cell (the paper's two-level
//             scheme with a perfect top level). For a T that does not divide the table's fine
//             grid, the restriction is computed from the table's pdf by the same quadrature.
//
// Quadrature: one point per fine texel of the environment table (the equal-area square, where every
// light density of the renderer is piecewise constant), then every texel that carries more than
// `refine_share` of the integral, of integral f^2 / p_env or of integral f^2 / p_bsdf, or whose
// midpoint error on one of them (estimated from the second differences to its neighbours) exceeds
// `refine_tolerance` of it, is evaluated again on a refine x refine grid of points (the lobe's peak, a
// sun's edge, the horizon), and refine times finer again while that still moves its integrals (up
// to 64 x 64 points per texel). Tables with the map's own texels (FineTexels::Map) are not piecewise
// constant on that grid: the analyzer analyzes their equal-area twins (same options, EqualArea)
// instead. Accuracy and cost are measured in docs/analyzer.md. Visibility is off by
// default, except for the one certain case: a closed transmissive surface's inside (local z < 0)
// never sees the environment (Material::set_closed_surface). With `visibility` every quadrature
// direction is traced.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "render/scene.h"
#include "render/strategy.h"

namespace envpis::render {

namespace analyzer_detail {
struct TexelCentres;
struct PassScratch;
}

struct AnalyzerOptions {
  std::vector<Strategy> strategies = all_strategies();
  Heuristic heuristic = Heuristic::Power;
  bool visibility = false;  ///< trace every quadrature direction (else: no occlusion but the certain one)
  int refine = 4;           ///< points per side in a refined texel, 1..64 (1: no refinement)
  double refine_share = 1e-4;  ///< a texel is refined when it carries more than this share, (0, 1]
  /// ...or when its midpoint error, estimated from its neighbours, exceeds this share, (0, 1]
  double refine_tolerance = 1e-7;
  std::vector<int> exact_levels{12, 24, 48};  ///< T of the exact-T limits, each 1..1024
  OracleOptions oracle;
  ProductSamplerOptions product;
  /// StrategyTables::product_compensation (the analyzer's product always uses the product: only On
  /// changes it)
  ProductCompensation product_compensation = ProductCompensation::Off;
  ImportanceTableOptions light_table;
};

/// Throws Error naming the first invalid option.
void validate(const AnalyzerOptions& options);

/// The variances at one shading point (each NaN where undefined, e.g. v_light of bsdf).
struct PointAnalysis {
  double integral[3] = {0, 0, 0};  ///< I per channel (radiance the pixel converges to)
  std::vector<double> v;           ///< per options.strategies: the renderer's one-sample estimator
  std::vector<double> v_light;     ///< per options.strategies: its light distribution alone
  std::vector<double> bias;        ///< per options.strategies: (E F - I) / I, channel mean (0 up to round-off)
  // v_light is the light sample's relative mean squared error: its variance when p_l > 0 wherever f > 0
  // (not so for mis-comp). The oracle's values are those of one draw of its jittered set-up.
  double v_product = 0;            ///< the exact product limit
  std::vector<double> v_exact;     ///< per options.exact_levels
  std::size_t evaluations = 0;     ///< quadrature directions evaluated
};

/// A shading point: the first hit of a camera ray.
struct ShadingPointRef {
  int object = -1;
  int pixel_x = 0, pixel_y = 0;
  Ray ray;
};

/// Camera rays through pixel centres of the scene camera's default image that hit an object, up to
/// `per_object` per object, spread evenly over each object's pixels in row-major order (deterministic).
std::vector<ShadingPointRef> first_hit_points(const Scene& scene, int per_object);

/// A strategy's tables for the scene's environment, built with the analyzer's options.
using StrategyTableSource = std::function<StrategyTables(Strategy)>;

class Analyzer {
 public:
  /// Builds the strategies' tables for the scene's environment (throws Error for invalid options).
  /// A caller that already built them with the same options (envpis compare) passes them as `source`.
  Analyzer(const Scene& scene, const AnalyzerOptions& options, const StrategyTableSource& source = {});
  ~Analyzer();
  Analyzer(const Analyzer&) = delete;
  Analyzer& operator=(const Analyzer&) = delete;

  /// The variances at the first hit of `camera_ray`; nullopt when the ray hits nothing or the
  /// integrand is 0 there. `jitter`: the oracle's per-point random bits. Thread-safe.
  std::optional<PointAnalysis> analyze(const Ray& camera_ray, std::uint64_t jitter = 0) const;

  const AnalyzerOptions& options() const { return options_; }
  /// Fine resolution of the environment table (the quadrature grid).
  int grid_resolution() const;
  double build_seconds() const { return build_seconds_; }

 private:
  void build_cell_masses();
  const Scene& scene_;
  AnalyzerOptions options_;
  std::vector<StrategyTables> tables_;  // one per distinct light distribution; [0]: the environment table
  std::vector<int> distribution_;       // per strategy: index into tables_ (-1: no light sample)
  std::vector<std::vector<double>> cell_mass_;  // per exact level, per cell: integral of p_env
  std::unique_ptr<const analyzer_detail::TexelCentres> centres_;  // what every point's first pass shares
  // The oracle's distribution when its cells' texels are the quadrature's (else -1), and the rows of
  // its cells: the first pass then builds its texel distributions from its own BSDF values.
  int shared_oracle_ = -1, oracle_rows_ = 0;
  // Per thread: the first pass's memory (analyze()), kept from point to point.
  mutable tbb::enumerable_thread_specific<std::unique_ptr<analyzer_detail::PassScratch>> pass_scratch_;
  // Per thread: a light sampler per table, prepared again at each point (their memory is kept).
  mutable tbb::enumerable_thread_specific<std::vector<LightSampler>> sampler_scratch_;
  double build_seconds_ = 0;
};

/// Geometric mean of the positive finite values (NaN when there is none).
double geometric_mean(const std::vector<double>& values);

/// One object's analyzed points and their pooled values, each per options().strategies (v, v_mean,
/// v_light) or per options().exact_levels (v_exact): geometric means over the points, except v_mean
/// (the arithmetic mean of v, as relMSE averages pixels). NaN where undefined.
struct ObjectAnalysis {
  int object = -1;
  std::vector<ShadingPointRef> refs;  // the points analyzed, in the order of `points`
  std::vector<PointAnalysis> points;
  std::vector<double> v, v_mean, v_light, v_exact;
  double v_product = 0;
};

/// The variance decomposition of issue 10 for one object (ratios of its geometric means; NaN when a
/// strategy or exact level it needs was not analyzed, or a value is undefined).
struct Decomposition {
  double env_over_product = 0;      ///< V(env) / V(product), light samples alone: the proxy's gain
  double product_over_exact12 = 0;  ///< V(product) / V(exact-12), light alone: the cost of the proxy's cell estimates
  double exact12_over_exact48 = 0;  ///< V(exact-12) / V(exact-48): the cost of the 12 x 12 top level
  double mis_over_product = 0;      ///< V(mis) / V(product), the renderer's estimators (what compare's relMSE measures)
};

/// The analysis of a scene's first-hit points (first_hit_points), pooled per object.
struct SceneAnalysis {
  std::vector<ObjectAnalysis> objects;  // objects with at least one analyzed point, in id order
  int per_object = 0;                   // points asked for per object
  std::size_t analyzed = 0, skipped = 0;  // points analyzed, points with no light (integrand 0)
  std::size_t evaluations = 0;          // quadrature directions over all points
  double seconds = 0;                   // wall time of the points' quadrature
};

/// Analyzes up to `per_object` first-hit points per object in parallel (in the caller's task arena);
/// a point's oracle jitter is mixed from `seed` and its pixel, so results do not depend on threads.
SceneAnalysis analyze_scene(const Analyzer& analyzer, const Scene& scene, int per_object, std::uint64_t seed);

Decomposition decompose(const ObjectAnalysis& object, const AnalyzerOptions& options);

}  // namespace envpis::render
