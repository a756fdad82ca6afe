// SPDX-License-Identifier: Apache-2.0
// Internal: the importance table's fine level. The equal-area square is cut into C x C cells of F x F
// texels each (N = C F texels per side; the cells are the table's top cells, or its sub-cells when it
// has them); every cell has its own distribution over its texels, independent of the others, so a
// sampler that has chosen a cell by any distribution above (environment, product, oracle) finishes
// the sample in that cell's CumulativeDistribution2DView.
//
// Layout: cell-major (the F x F texels of a cell are contiguous, row-major inside the cell), and per
// cell the running sums in CumulativeDistribution2DView's layout, so both searches of a sample read
// contiguous memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "envpis/discrete_distribution_2d.h"
#include "envpis_assert.h"

namespace envpis::detail {

// Sums over a leaf's texel centres d: importance-weighted (v d, v) and plain (d, n), each texel
// counted by its solid angle (equal-area texels: 1 each).
struct DirectionSums {
  double v[3] = {0, 0, 0}, w = 0, d[3] = {0, 0, 0}, n = 0;
  void add(const DirectionSums& o) {
    for (int k = 0; k < 3; ++k) v[k] += o.v[k], d[k] += o.d[k];
    w += o.w;
    n += o.n;
  }
  void add(Vec3 dir, double importance, double measure) {
    v[0] += importance * dir.x, v[1] += importance * dir.y, v[2] += importance * dir.z, w += importance;
    d[0] += measure * dir.x, d[1] += measure * dir.y, d[2] += measure * dir.z, n += measure;
  }
};

class FineLevel {
 public:
  FineLevel() = default;
  FineLevel(int cells, int per_cell);  ///< C, F; every texel's importance 0

  int cells() const { return C_; }
  int per_cell() const { return F_; }
  int resolution() const { return C_ * F_; }

  /// Index of texel (x, y), 0 <= x, y < N, in values(); separable: row_base(y) + col_base(x).
  std::size_t index(int x, int y) const { return std::size_t(row_base_[y]) + col_base_[x]; }
  std::vector<float>& values() { return func_; }
  const std::vector<float>& values() const { return func_; }

  /// Builds the per-cell distributions from values(); returns each cell's total importance.
  std::vector<double> build();
  /// The distribution over cell c's texels (c = y * C + x); all pmf 0 if the cell has no importance.
  CumulativeDistribution2DView cell(int c) const {
    ENVPIS_ASSERT(c >= 0 && c < C_ * C_);
    const std::size_t o = static_cast<std::size_t>(c) * F_ * F_;
    return {&func_[o], &cdf_[o], cell_sum_[static_cast<std::size_t>(c)], F_};
  }

  std::size_t bytes_used() const;

 private:
  int C_ = 1, F_ = 1;
  std::vector<std::uint32_t> row_base_, col_base_;  // N each: index(x, y) = row_base_[y] + col_base_[x]
  std::vector<float> func_;      // N^2 importance values, cell-major
  std::vector<float> cdf_;       // N^2 running sums, per cell
  std::vector<float> cell_sum_;  // C^2
};

}  // namespace envpis::detail
