// SPDX-License-Identifier: Apache-2.0
#include "envpis/discrete_distribution_2d.h"

#include <cstring>

#include "envpis_assert.h"

namespace envpis {

namespace {
constexpr int kPad = 16;  // padded_size() is a multiple of this (the widest kernel's lane count)

// A row's total (update() runs per shading point, so these sums are written for speed): four partial
// sums keep the adds independent. Rows whose width is a multiple of 4 (the top level's 12, the
// sub-cells' 4) take their partial sums in vector lanes, four rows at once; both ways give the same
// sums, lane k adding row[k], row[k + 4], ... left to right, then (a0 + a1) + (a2 + a3).
float row_total(const float* row, int w) {
  float a0 = 0, a1 = 0, a2 = 0, a3 = 0;
  int k = 0;
  for (; k + 4 <= w; k += 4) {
    a0 += row[k];
    a1 += row[k + 1];
    a2 += row[k + 2];
    a3 += row[k + 3];
  }
  for (; k < w; ++k) a0 += row[k];
  return (a0 + a1) + (a2 + a3);
}

using Lanes4 = float __attribute__((vector_size(16)));
inline Lanes4 load4(const float* p) {
  Lanes4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline Lanes4 row_lanes(const float* row, int w) {  // w a multiple of 4
  Lanes4 a = load4(row);
  for (int k = 4; k < w; k += 4) a += load4(row + k);
  return a;
}
// Four rows' totals from their lanes, as one vector: a transpose, then row_total's (a0 + a1) + (a2 + a3).
inline Lanes4 four_totals(Lanes4 a, Lanes4 b, Lanes4 c, Lanes4 d) {
  const Lanes4 ab_lo = __builtin_shufflevector(a, b, 0, 4, 1, 5);
  const Lanes4 ab_hi = __builtin_shufflevector(a, b, 2, 6, 3, 7);
  const Lanes4 cd_lo = __builtin_shufflevector(c, d, 0, 4, 1, 5);
  const Lanes4 cd_hi = __builtin_shufflevector(c, d, 2, 6, 3, 7);
  const Lanes4 lane0 = __builtin_shufflevector(ab_lo, cd_lo, 0, 1, 4, 5);  // lane 0 of a, b, c, d
  const Lanes4 lane1 = __builtin_shufflevector(ab_lo, cd_lo, 2, 3, 6, 7);
  const Lanes4 lane2 = __builtin_shufflevector(ab_hi, cd_hi, 0, 1, 4, 5);
  const Lanes4 lane3 = __builtin_shufflevector(ab_hi, cd_hi, 2, 3, 6, 7);
  return (lane0 + lane1) + (lane2 + lane3);
}
}  // namespace

DiscreteDistribution2D::DiscreteDistribution2D(int width, int height) : w_(width), h_(height) {
  if (width < 1 || height < 1) throw Error("a 2D distribution needs at least one cell");
  const std::size_t n = static_cast<std::size_t>(width) * height;
  mass_.assign((n + kPad - 1) / kPad * kPad, 0.0f);
  row_sum_.assign(static_cast<std::size_t>(height), 0.0f);
  row_cdf_.assign(static_cast<std::size_t>(height), 0.0f);
}

DiscreteDistribution2D::DiscreteDistribution2D(const float* masses, int width, int height)
    : DiscreteDistribution2D(width, height) {
  std::copy(masses, masses + static_cast<std::size_t>(width) * height, mass_.begin());
  update();
}

// The rows' totals in order, for w = W (W > 0, known when compiled: the loops unroll) or w_ (W = 0).
template <int W, class OnRow>
float DiscreteDistribution2D::accumulate_rows_of(OnRow on_row) const {
  const int w = W > 0 ? W : w_;
  const std::size_t stride = static_cast<std::size_t>(w);
  float run = 0;
  int r = 0;
  const float* m = mass_.data();
  if (w % 4 == 0) {
    for (; r + 4 <= h_; r += 4, m += 4 * stride) {
      const Lanes4 t = four_totals(row_lanes(m, w), row_lanes(m + stride, w), row_lanes(m + 2 * stride, w),
                                   row_lanes(m + 3 * stride, w));
      for (int k = 0; k < 4; ++k) on_row(r + k, t[k], run += t[k]);
    }
  }
  for (; r < h_; ++r, m += stride) {  // the rows left over: row_total's sums are four_totals' (above)
    const float t = row_total(m, w);
    on_row(r, t, run += t);
  }
  return run;
}

template <class OnRow>
float DiscreteDistribution2D::accumulate_rows(OnRow on_row) const {
  if (w_ == 12) return accumulate_rows_of<12>(on_row);  // the product's top level
  if (w_ == 4) return accumulate_rows_of<4>(on_row);    // its sub-cells
  return accumulate_rows_of<0>(on_row);
}

float DiscreteDistribution2D::update() {
  const float run = accumulate_rows([this](int r, float t, float cdf) {
    row_sum_[r] = t;
    row_cdf_[r] = cdf;
  });
  total_ = run;
  inv_total_ = valid() ? 1.0f / run : 0.0f;
  return run;
}

float DiscreteDistribution2D::sum() const {
  return accumulate_rows([](int, float, float) {});
}

Point2 DiscreteDistribution2D::invert(int x, int y, Point2 offset) const {
  ENVPIS_ASSERT(x >= 0 && x < w_ && y >= 0 && y < h_);
  if (!valid()) return {0.5f, 0.5f};
  const float* row = mass_.data() + static_cast<std::size_t>(y) * w_;
  float before = 0;
  for (int i = 0; i < x; ++i)
    if (row[i] > 0) before += row[i];
  const float row_start = y > 0 ? row_cdf_[y - 1] : 0.0f;
  const float ux = row_sum_[y] > 0 ? (before + offset.x * row[x]) / row_sum_[y] : 0.5f;
  const float uy = (row_start + offset.y * row_sum_[y]) / total_;
  return {detail::clamp_unit(ux), detail::clamp_unit(uy)};
}

double CumulativeDistribution2DView::build(const float* masses, int n, float* cdf) {
  ENVPIS_ASSERT(n >= 1);
  const std::size_t count = static_cast<std::size_t>(n) * n;
  double total = 0;
  for (std::size_t i = 0; i < count; ++i) total += masses[i];
  // Uniform sums for a zero distribution keep every search well defined.
  const bool uniform = !(total > 0);
  double run = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * n + x;
      const float sum = uniform ? float(i + 1) / float(count) : static_cast<float>((run += masses[i]) / total);
      if (x < n - 1)
        cdf[n + static_cast<std::size_t>(y) * (n - 1) + x] = sum;
      else
        cdf[y] = sum;
    }
  }
  cdf[n - 1] = 1.0f;
  return total;
}

Point2 CumulativeDistribution2DView::invert(int x, int y, Point2 offset) const {
  ENVPIS_ASSERT(x >= 0 && x < n_ && y >= 0 && y < n_);
  const float row_start = y > 0 ? cdf_[y - 1] : 0.0f, row_end = cdf_[y];
  const float* row = cdf_ + n_ + static_cast<std::size_t>(y) * (n_ - 1);
  const float c0 = x > 0 ? row[x - 1] : row_start, c1 = x < n_ - 1 ? row[x] : row_end;
  const float row_mass = row_end - row_start;
  const float ux = row_mass > 0 ? (c0 + offset.x * (c1 - c0) - row_start) / row_mass : 0.5f;
  return {detail::clamp_unit(ux), detail::clamp_unit(row_start + offset.y * row_mass)};
}

}  // namespace envpis
