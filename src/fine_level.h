// Internal: the importance table's fine level. The equal-area square is cut into T x T top cells of
// F x F texels each (N = T F texels per side); every top cell has its own piecewise-constant
// distribution over its texels, independent of the others, so a sampler that has chosen a cell by any
// top-level distribution (environment, product, oracle) finishes the sample here.
//
// Layout: cell-major (the F x F texels of a cell are contiguous, row-major inside the cell), and per
// cell the running sums normalized to end at 1, stored with the F row ends first (the marginal) and
// then each row's other F - 1 entries, so both searches of a sample read contiguous memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "envpis/common.h"

namespace envpis::detail {

class FineLevel {
 public:
  FineLevel() = default;
  FineLevel(int top, int per_cell);  ///< T, F; every texel's importance 0

  int top() const { return T_; }
  int per_cell() const { return F_; }
  int resolution() const { return T_ * F_; }

  /// Index of texel (x, y), 0 <= x, y < N, in values(); separable: row_base(y) + col_base(x).
  std::size_t index(int x, int y) const { return std::size_t(row_base_[y]) + col_base_[x]; }
  std::vector<float>& values() { return func_; }
  const std::vector<float>& values() const { return func_; }

  /// Builds the per-cell distributions from values(); returns each cell's total importance.
  std::vector<double> build();
  /// Total importance of cell c (0: the cell is never sampled).
  float cell_sum(int c) const { return cell_sum_[static_cast<std::size_t>(c)]; }

  struct Sample {
    Point2 p;            ///< equal-area point, inside cell c
    float pdf = 0;       ///< density inside the cell, the cell having area 1
    bool interior = false;  ///< far enough inside its texel that pdf(c, p of its direction) == pdf
  };
  /// A texel of cell c with u.y (row) and u.x (column), then the point inside it from u's remainder.
  Sample sample(int c, Point2 u) const;
  /// Density of cell c's distribution at equal-area point p (clamped into the cell), cell area 1.
  float pdf(int c, Point2 p) const;
  /// The u that sample(c, u) maps to p, for p inside cell c.
  Point2 invert(int c, Point2 p) const;

  std::size_t bytes_used() const;

 private:
  int T_ = 1, F_ = 1;
  std::vector<std::uint32_t> row_base_, col_base_;  // N each: index(x, y) = row_base_[y] + col_base_[x]
  std::vector<float> func_;      // N^2 importance values, cell-major
  std::vector<float> cdf_;       // N^2 normalized running sums per cell, row ends first
  std::vector<float> cell_sum_;  // T^2
};

}  // namespace envpis::detail
