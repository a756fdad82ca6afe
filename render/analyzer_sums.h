// SPDX-License-Identifier: Apache-2.0
// The analyzer's quadrature sums (render/analyzer.h): what each quadrature point adds at one shading
// point, and the relative variances the sums give. Internal to the analyzer.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "render/analyzer.h"
#include "render/analyzer_integrand.h"

namespace envpis::render::analyzer_detail {

/// Per strategy: integral of w_l^2 f^2 / p_l, w_b^2 f^2 / p_b, w_l f and w_b f, per channel.
struct StrategySums {
  std::array<double, 3> a_light{}, a_bsdf{}, b_light{}, b_bsdf{};
};

/// Running quadrature sums of one shading point.
struct Sums {
  std::array<double, 3> integral{};
  double integral_blind = 0;
  std::vector<StrategySums> strategies;
  std::array<std::array<double, 3>, kMaxDistributions> light_sq{}, light_mean{};  // f^2/p and f where p > 0
  std::array<double, 3> product_sq{};  // f^2 / f_blind
  /// Per exact level, per cell: integral of f_blind, then f^2 / p_env per channel. Only the levels that
  /// are their own source are summed (the others stay empty and are aggregated by finish()).
  std::vector<std::vector<std::array<double, 4>>> exact;
  /// Per exact level, the level its cells are summed from: the finest level it divides (itself when none).
  std::vector<std::size_t> exact_source;

  /// Sets exact_source for these levels and sizes the summed levels' cells.
  void init_exact(const std::vector<int>& levels);
};

/// The cells [c0, c1] of a grid of t cells per side that the interval [lo, lo + size) meets (size at
/// most one cell), and the share f0 of the interval that lies in c0.
struct Split {
  int c0, c1;
  double f0;
};
inline Split split(double lo, double size, int t) {
  const double a = lo * t, b = (lo + size) * t;
  const int c0 = std::min(static_cast<int>(a), t - 1);
  const int c1 = std::min(static_cast<int>(std::ceil(b)) - 1, t - 1);
  if (c1 <= c0) return {c0, c0, 1.0};
  return {c0, c1, (double(c1) - a) / (b - a)};
}

/// A quadrature point: the square [x, x + size) x [y, y + size) of the equal-area square it stands for,
/// its solid angle w (negative: remove it) and its centre.
struct QuadraturePoint {
  double x, y, size, w;
  Point2 centre() const { return {float(x + 0.5 * size), float(y + 0.5 * size)}; }
};

/// The splits of the first pass's texel columns (= rows) for each exact level: split(x / n, 1 / n, t).
using TexelSplits = std::vector<std::vector<Split>>;
TexelSplits texel_splits(int n, const std::vector<int>& levels);

/// Quadrature points to add to the sums: values v[j] at points q[j], j < count. In the first pass
/// (q null) the points are fine texels, `texel[j]` = (x, y), each of solid angle `texel_area`, whose
/// splits for the exact levels come from `splits` (computed once per point instead of once per texel).
struct Batch {
  const DirectionValues* v;
  const QuadraturePoint* q;
  std::size_t count;
  const std::array<int, 2>* texel = nullptr;
  const TexelSplits* splits = nullptr;
  double texel_area = 0;
};

/// Adds a batch to the sums, one running sum at a time over a chunk of points (each strategy's sums
/// stay in registers): every sum gets the same terms in the same order as point by point.
void accumulate(const Batch& b, const AnalyzerOptions& o, const std::vector<int>& distribution, Sums& s);

/// One point.
void accumulate(const DirectionValues& v, const QuadraturePoint& q, const AnalyzerOptions& o,
                const std::vector<int>& distribution, Sums& s);

/// Turns the sums into relative variances (channel means over the channels with I > 0); false when the
/// point has no light. `cell_mass`: per exact level, per cell, the integral of the environment density.
bool finish(const Sums& s, const AnalyzerOptions& o, const std::vector<int>& distribution,
            const std::vector<std::vector<double>>& cell_mass, PointAnalysis* r);

}  // namespace envpis::render::analyzer_detail
