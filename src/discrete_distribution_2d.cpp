// SPDX-License-Identifier: Apache-2.0
#include "envpis/discrete_distribution_2d.h"

#include "envpis_assert.h"

namespace envpis {

namespace {
constexpr int kPad = 16;  // padded_size() is a multiple of this (the widest kernel's lane count)

// Four partial sums per row keep the adds independent (update() runs per shading point).
float row_total(const float* row, int w) {
  if (w == 4) return (row[0] + row[1]) + (row[2] + row[3]);  // the sub-cells: the loop's sums below
  if (w == 12)  // the default top level: the same sums without loop control
    return ((row[0] + row[4]) + row[8] + ((row[1] + row[5]) + row[9])) +
           (((row[2] + row[6]) + row[10]) + ((row[3] + row[7]) + row[11]));
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

template <class OnRow>
float DiscreteDistribution2D::accumulate_rows(OnRow on_row) const {
  float run = 0;
  for (int r = 0; r < h_; ++r) {
    const float t = row_total(mass_.data() + static_cast<std::size_t>(r) * w_, w_);
    run += t;
    on_row(r, t, run);
  }
  return run;
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
