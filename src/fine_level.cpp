#include "fine_level.h"

#include <algorithm>

#include "envpis_assert.h"
#include "envpis/discrete_distribution_2d.h"
#include "parallel.h"

namespace envpis::detail {

namespace {
struct SplitSample {
  int x = 0, y = 0;  // texel inside the cell
  Point2 offset;     // inside the texel, [0,1)
};

// A row with u.y among the row ends, then a column inside it with u.x (see fine_level.h's layout).
SplitSample sample_split(const float* split, int F, Point2 u) {
  const float uy = clamp_unit(u.y), ux = clamp_unit(u.x);
  SplitSample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(split, split + F, uy) - split, F - 1));
  const float row_start = s.y > 0 ? split[s.y - 1] : 0.0f;
  const float row_end = split[s.y];
  const float row_mass = row_end - row_start;
  s.offset.y = row_mass > 0 ? clamp_unit((uy - row_start) / row_mass) : 0.5f;
  const float target = row_start + ux * row_mass;
  const float* row = split + F + static_cast<std::size_t>(s.y) * (F - 1);  // entries 0 .. F-2
  s.x = static_cast<int>(std::upper_bound(row, row + (F - 1), target) - row);  // F - 1: the last column
  if (s.x == F - 1 && !(row_end > target)) {  // rounding at the row's end: last column with mass
    while (s.x > 0 && (s.x == F - 1 ? row_end : row[s.x]) <= row[s.x - 1]) --s.x;
  }
  const float c0 = s.x > 0 ? row[s.x - 1] : row_start;
  const float c1 = s.x < F - 1 ? row[s.x] : row_end;
  const float mass = c1 - c0;
  s.offset.x = mass > 0 ? clamp_unit((target - c0) / mass) : 0.5f;
  return s;
}
}  // namespace

FineLevel::FineLevel(int top, int per_cell)
    : T_(top), F_(per_cell), func_(static_cast<std::size_t>(top) * per_cell * top * per_cell, 0.0f) {
  const int N = top * per_cell;
  row_base_.resize(N);
  col_base_.resize(N);
  for (int i = 0; i < N; ++i) {
    const std::size_t c = static_cast<std::size_t>(i / per_cell), l = static_cast<std::size_t>(i % per_cell);
    row_base_[i] = static_cast<std::uint32_t>((c * top * per_cell + l) * per_cell);
    col_base_[i] = static_cast<std::uint32_t>(c * per_cell * per_cell + l);
  }
}

std::vector<double> FineLevel::build() {
  const int cells = T_ * T_;
  const std::size_t per = static_cast<std::size_t>(F_) * F_;
  cdf_.assign(func_.size(), 0.0f);
  cell_sum_.assign(static_cast<std::size_t>(cells), 0.0f);
  std::vector<double> sums(static_cast<std::size_t>(cells), 0.0);
  parallel_for(0, cells, [&](int begin, int end) {
    std::vector<float> cdf(per);  // row-major running sums, normalized to end at 1
    for (int c = begin; c < end; ++c) {
      const float* f = &func_[c * per];
      double total = 0;
      for (std::size_t i = 0; i < per; ++i) total += f[i];
      sums[c] = total;
      if (total > 0) {
        double run = 0;
        for (std::size_t i = 0; i < per; ++i) cdf[i] = static_cast<float>((run += f[i]) / total);
      } else {  // a zero cell (only with floor 0): uniform, never chosen because its probability is 0
        for (std::size_t i = 0; i < per; ++i) cdf[i] = float(i + 1) / float(per);
      }
      cdf[per - 1] = 1.0f;
      float* out = &cdf_[c * per];
      for (int y = 0; y < F_; ++y) {
        out[y] = cdf[y * F_ + F_ - 1];
        for (int x = 0; x < F_ - 1; ++x) out[F_ + y * (F_ - 1) + x] = cdf[y * F_ + x];
      }
      cell_sum_[c] = static_cast<float>(total);
    }
  });
  return sums;
}

FineLevel::Sample FineLevel::sample(int c, Point2 u) const {
  ENVPIS_ASSERT(c >= 0 && c < T_ * T_);
  const std::size_t per = static_cast<std::size_t>(F_) * F_;
  const SplitSample s = sample_split(&cdf_[c * per], F_, u);
  const int cx = c % T_, cy = c / T_, N = T_ * F_;
  Sample out;
  const float f = func_[c * per + static_cast<std::size_t>(s.y) * F_ + s.x];
  out.pdf = cell_sum_[c] > 0 ? f / cell_sum_[c] * float(F_) * float(F_) : 0.0f;
  // The square -> sphere -> square round trip is accurate to a few 1e-6 (tests/test_equal_area.cpp);
  // 2% of a texel is at least 7e-6 for N <= 2904 and scales with the texel.
  constexpr float kMargin = 0.02f;
  out.interior = s.offset.x > kMargin && s.offset.x < 1 - kMargin && s.offset.y > kMargin &&
                 s.offset.y < 1 - kMargin && N <= 2904;
  // Keep the point kEdge inside its top cell. Rounding can put it on the cell's far edge (an offset
  // of 1 - 2^-24 in the last texel), and a point within round-off of the edge can come back from
  // square -> sphere -> square in the neighbouring cell, whose product weight may be 0 (a cell wholly
  // below an opaque proxy's horizon): the sample would get pdf 0 where pdf() integrates to 1. The
  // move is under 2% of a texel for N <= 1000 and such samples are never `interior`, so their density
  // is looked up again from the direction, which finds this cell.
  constexpr float kEdge = 2e-5f;
  const float inv_T = 1.0f / float(T_);
  const float px = (float(cx * F_ + s.x) + s.offset.x) / float(N);
  const float py = (float(cy * F_ + s.y) + s.offset.y) / float(N);
  out.p = {std::clamp(px, float(cx) * inv_T + kEdge, float(cx + 1) * inv_T - kEdge),
           std::clamp(py, float(cy) * inv_T + kEdge, float(cy + 1) * inv_T - kEdge)};
  return out;
}

float FineLevel::pdf(int c, Point2 p) const {
  const int N = T_ * F_;
  const int cx = c % T_, cy = c / T_;
  // p may sit on the cell's boundary through rounding: clamp into the cell.
  const int x = std::clamp(static_cast<int>(p.x * N), cx * F_, cx * F_ + F_ - 1);
  const int y = std::clamp(static_cast<int>(p.y * N), cy * F_, cy * F_ + F_ - 1);
  if (!(cell_sum_[c] > 0)) return 0.0f;
  return func_[index(x, y)] / cell_sum_[c] * float(F_) * float(F_);
}

Point2 FineLevel::invert(int c, Point2 p) const {
  const int N = T_ * F_;
  const int cx = c % T_, cy = c / T_;
  const int x = std::clamp(static_cast<int>(p.x * N), cx * F_, cx * F_ + F_ - 1);
  const int y = std::clamp(static_cast<int>(p.y * N), cy * F_, cy * F_ + F_ - 1);
  const float fx = clamp_unit(p.x * N - float(x)), fy = clamp_unit(p.y * N - float(y));
  const int lx = x - cx * F_, ly = y - cy * F_;
  const float* split = &cdf_[static_cast<std::size_t>(c) * F_ * F_];
  const float row_start = ly > 0 ? split[ly - 1] : 0.0f, row_end = split[ly];
  const float* row = split + F_ + static_cast<std::size_t>(ly) * (F_ - 1);
  const float c0 = lx > 0 ? row[lx - 1] : row_start, c1 = lx < F_ - 1 ? row[lx] : row_end;
  const float row_mass = row_end - row_start;
  const float ux = row_mass > 0 ? (c0 + fx * (c1 - c0) - row_start) / row_mass : 0.5f;
  return {clamp_unit(ux), clamp_unit(row_start + fy * row_mass)};
}

std::size_t FineLevel::bytes_used() const {
  return (func_.capacity() + cdf_.capacity() + cell_sum_.capacity()) * sizeof(float);
}

}  // namespace envpis::detail
