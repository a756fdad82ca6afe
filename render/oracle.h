// SPDX-License-Identifier: Apache-2.0
// The oracle light distribution: a per-shading-point top level over the cells of a fine light table
// (48 x 48 by default), each weighted from an estimate of its true share of the integrand
// g = BSDF x |cos| x radiance (channel average), and inside the chosen cell a distribution over the
// cell's fine texels weighted by g itself. It is the limit the product sampler is measured against
// (docs/analyzer.md, "The oracle"): the paper's two-level scheme with a (nearly) perfect top level,
// and a product, not the environment alone, inside the cell.
//
// Why the texels: a lobe narrower than a cell (GGX alpha 0.02 is a few degrees, a 48 x 48 cell about
// four) fills a small part of its cell, and the environment's density inside the cell puts most
// light samples where the BSDF is nearly 0; the product sampler, whose sub-cells give it the same
// 48 x 48 resolution, then did better at that roughness. Weighting each texel by g at its centre
// (with the texel's mean radiance) follows the lobe down to the table's resolution. It costs one BSDF
// evaluation and pdf per texel of every cell that sample() or pdf() visits, built on first use after
// prepare() and kept until the next.
//
// The share of a cell, the integral of g over it, is estimated per shading point by two techniques
// combined with the balance heuristic:
//   - points drawn from the cell's radiance distribution (each fine texel's mean radiance, computed
//     once per map), so g / density varies only as the BSDF does: a small sun inside a cell costs
//     nothing (drawing from the table's importance instead failed there: near a small source the
//     table raises texels to 1/K of its peak, and most such texels see only sky);
//   - BSDF-sampled directions, which find a lobe narrower than a cell wherever it lies (a fixed
//     number of evaluations per cell misses it).
// A first pass gives every cell one point (16 to a cell that straddles the horizon of a surface seen
// from above only: its brightest texels may lie below and say nothing of the rest); a second gives
// further points to the cells in proportion to their first estimate (the lobe's peak, a sun).
//
// The weights: the estimated share alone (mis_compensation off) makes the best light sample, but
// next to a BSDF sample combined by MIS the light sample should go where the BSDF sample does not:
// one light and one BSDF sample have least variance under the balance heuristic when their
// densities sum to a multiple of g, so each cell gets max(share / 4, 2 share - P_bsdf(cell)), with
// P_bsdf(cell) estimated by the same points (the compensation of Karlik et al. 2019, per cell).
//
// The texels are weighted by the same rule, per texel: max(g / 4, 2 g - p_bsdf), g as a share density
// of the estimated integral and p_bsdf the BSDF sample's density at the texel's centre.
//
// Unbiased whatever the estimates: pdf() is exactly the density sample() draws from (piecewise
// constant on the table's texels), every cell a light sample can use keeps at least 1e-3 of its
// environment share, and inside a cell a small part of the probability follows the table's
// importance, so no direction with radiance depends on BSDF samples alone.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "envpis/envpis.h"
#include "render/strategy.h"

namespace envpis::render {

/// What the oracle needs per environment map, shared by all threads: the light table (whose top
/// level is the oracle's grid), each fine texel's mean radiance, and each cell's fine distribution
/// as a separate F x F distribution, so points can be drawn inside one given cell.
class OracleCells {
 public:
  OracleCells(const EnvironmentMap& env, std::shared_ptr<const ImportanceTable> table);
  const ImportanceTable& table() const { return *table_; }
  /// Mean radiance over texel (x, y) of cell c (0 <= x, y < F): what a light sample of that texel
  /// sees on average (the texel's importance may be raised above it near a small bright source).
  const Rgb& radiance(int c, int x, int y) const { return radiance_[index(c, x, y)]; }
  /// Cell c's fine distribution over its F x F texels (invalid when the cell has no importance).
  const DiscreteDistribution2D& cell(int c) const { return cells_[static_cast<std::size_t>(c)]; }

 private:
  std::size_t index(int c, int x, int y) const {
    const std::size_t F = static_cast<std::size_t>(table_->cell_resolution());
    return (static_cast<std::size_t>(c) * F + static_cast<std::size_t>(y)) * F + static_cast<std::size_t>(x);
  }
  std::shared_ptr<const ImportanceTable> table_;
  std::vector<DiscreteDistribution2D> cells_;
  std::vector<Rgb> radiance_;  // per fine texel, cell-major
};

/// Per-thread oracle distribution (not thread-safe, not even its const sample() and pdf(), which fill
/// a cache). prepare() costs a few thousand BSDF and environment evaluations (OracleOptions); the
/// first sample() or pdf() in a cell costs a BSDF evaluation and pdf per texel of the cell.
class OracleSampler {
 public:
  OracleSampler(std::shared_ptr<const OracleCells> cells, const OracleOptions& options);
  void prepare(const ShadingContext& sc);
  DirectionSample sample(Point2 u) const;
  float pdf(Vec3 wi) const;
  /// pdf() at the direction of equal-area point p, given p (ImportanceTable::pdf_square).
  float pdf_square(Point2 p) const;
  /// The prepared top level (for tests): cell weights, or invalid when no cell has any.
  const DiscreteDistribution2D& top() const { return top_; }

  /// The material at a texel's centre, as the caller (the analyzer's quadrature, which evaluates the
  /// same directions) found it: the local cosine there, and where `known`, f = eval (no cosine) and
  /// its pdf; elsewhere the oracle evaluates them itself, if it needs them.
  struct TexelBsdf {
    Rgb f;
    float pdf = 0, cos = 0;
    bool known = false;
  };
  /// Builds cell c's texel distribution now, as the first sample() or pdf() in the cell would, from
  /// `given` (the cell's F x F texel centres, row-major) where known: the same values give the same
  /// distribution. No-op when the cell is built since prepare() or has no weight.
  void build_texels(int c, const TexelBsdf* given) const;
  /// pdf() in texel (x, y) of cell c (0 <= x, y < F): pdf_square() of a point in that texel.
  float texel_pdf(int c, int x, int y) const;

 private:
  struct Point {
    int cell;
    float g;   // f |cos| L, channel average (0 where the light sample cannot reach)
    float q;   // solid-angle density of the cell's fine distribution
    float pb;  // the material's BSDF sampling density
  };
  struct RowDraw {  // a point of a cell whose row is drawn, not yet its texel
    int cell;
    float ux;
    DiscreteDistribution2D::Sample s;
  };
  struct Draw {  // a point drawn from a cell's distribution, not yet evaluated
    int cell;
    Point2 p;
    float q;
    const Rgb* radiance;
  };
  void light_points(const ShadingContext& sc, int c, int k, int pass);  // k x k draws in cell c into rows_
  void place_draws();                             // every row draw's texel: rows_ into draws_
  void evaluate_draws(const ShadingContext& sc);  // every draw into points_
  Point evaluate(const ShadingContext& sc, Point2 p, int c, float q, Rgb radiance, bool skip_below) const;
  void estimate();  // cell_sum_ from points_ and count_
  // Cell c's F x F texel weights, with the material's values from `given` where known (may be null).
  void texel_weights(int c, float* out, const TexelBsdf* given) const;
  // Cell c's texel distribution, built on first use.
  const DiscreteDistribution2D& texels(int c, const TexelBsdf* given = nullptr) const;

  std::shared_ptr<const OracleCells> cells_;
  OracleOptions options_;
  DiscreteDistribution2D top_;
  std::vector<Point> points_;     // every evaluated direction of this shading point
  std::vector<RowDraw> rows_;     // drawn rows, their texels to be drawn
  std::vector<Draw> draws_;       // drawn, to be evaluated
  std::vector<int> count_;        // per cell: points drawn from its fine distribution
  std::vector<int> active_;       // cells a light sample can use
  std::vector<bool> horizon_;     // per active cell: it straddles the horizon of a surface seen from above only
  std::vector<double> cell_sum_;  // per cell: the estimate of integral over the cell of g
  std::vector<double> bsdf_mass_;  // per cell: the estimate of the BSDF sample's probability to land in it
  std::vector<double> weight_;     // per cell: its weight before normalization and the floor
  bool valid_ = false;
  ShadingContext sc_;   // the prepared shading point (its frame and material outlive sample and pdf)
  double total_ = 0;    // the estimate of the integral of g over the sphere
  // The texel distributions of the cells sample() or pdf() used since prepare(): cell -> slot in pool_.
  mutable std::vector<int> slot_;
  mutable std::vector<int> built_;
  mutable std::deque<DiscreteDistribution2D> pool_;
};

}  // namespace envpis::render
