// SPDX-License-Identifier: Apache-2.0
#include "fine_level.h"

#include "huge_pages.h"
#include "parallel.h"

namespace envpis::detail {

FineLevel::FineLevel(int cells, int per_cell) : C_(cells), F_(per_cell) {
  assign_fresh(func_, static_cast<std::size_t>(cells) * per_cell * cells * per_cell, 0.0f);  // huge_pages.h
  const int N = cells * per_cell;
  row_base_.resize(N);
  col_base_.resize(N);
  for (int i = 0; i < N; ++i) {
    const std::size_t c = static_cast<std::size_t>(i / per_cell), l = static_cast<std::size_t>(i % per_cell);
    row_base_[i] = static_cast<std::uint32_t>((c * cells * per_cell + l) * per_cell);
    col_base_[i] = static_cast<std::uint32_t>(c * per_cell * per_cell + l);
  }
}

std::vector<double> FineLevel::build() {
  const int cells = C_ * C_;
  const std::size_t per = static_cast<std::size_t>(F_) * F_;
  assign_fresh(cdf_, func_.size(), 0.0f);
  cell_sum_.assign(static_cast<std::size_t>(cells), 0.0f);
  std::vector<double> sums(static_cast<std::size_t>(cells), 0.0);
  parallel_for(0, cells, [&](int begin, int end) {
    for (int c = begin; c < end; ++c) {
      sums[c] = CumulativeDistribution2DView::build(&func_[c * per], F_, &cdf_[c * per]);
      cell_sum_[c] = static_cast<float>(sums[c]);
    }
  });
  return sums;
}

std::size_t FineLevel::bytes_used() const {
  return (func_.capacity() + cdf_.capacity() + cell_sum_.capacity()) * sizeof(float);
}

}  // namespace envpis::detail
