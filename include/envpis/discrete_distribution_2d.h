// SPDX-License-Identifier: Apache-2.0
// A discrete distribution over the cells of a w x h grid that also hands back where inside its cell a
// sample landed, so a second level (a fine table, a warp) can reuse the remainder of u and stratified
// u stay stratified (as pbrt-v4's PiecewiseConstant2D and Mitsuba's DiscreteDistribution2D do).
//
// Layout: row totals and their running sums only. A sample finds its row among the h running sums
// (binary search), then scans that row's w masses. No per-cell running sums are stored, so rebuilding
// the distribution per shading point (the product sampler's top level) costs one pass over the masses.
//
// Rebuilding without allocation: write the masses through values(), then call update(). values() has
// room for padded_size() floats, w * h rounded up to a multiple of 16, so vector code can store whole
// registers; entries past w * h are ignored.
//
// Masses must be >= 0. Cells whose mass is 0 or NaN are never chosen. A distribution whose total is
// not a positive normal float (all zero, NaN, Inf, or below FLT_MIN, whose reciprocal would overflow)
// is not valid(): sample() and pmf() must not be used then.
//
// CumulativeDistribution2DView is the other storage: an n x n distribution kept as its running sums,
// for distributions built once and sampled many times (the importance table's fine level keeps one
// per cell, all in one array). Both of its searches are binary.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "envpis/common.h"

namespace envpis {

namespace detail {
/// Starts loading the cache lines of p[0, n) into the cache (every 64 bytes, and the last).
inline void prefetch_floats(const float* p, int n) {
  for (int i = 0; i < n; i += 16) __builtin_prefetch(p + i);
  if (n > 0) __builtin_prefetch(p + n - 1);
}
}  // namespace detail

class DiscreteDistribution2D {
 public:
  struct Sample {
    int x = 0, y = 0;  ///< the chosen cell
    Point2 offset;     ///< where inside it, in [0,1)^2: u's remainder after the choice
    float pmf = 0;     ///< probability of the cell
  };

  DiscreteDistribution2D() = default;
  /// w x h cells of mass 0 (not valid() until masses are written and update() is called).
  DiscreteDistribution2D(int width, int height);
  /// Copies w * h row-major masses and calls update().
  DiscreteDistribution2D(const float* masses, int width, int height);

  int width() const { return w_; }
  int height() const { return h_; }
  int padded_size() const { return static_cast<int>(mass_.size()); }
  float* values() { return mass_.data(); }
  const float* values() const { return mass_.data(); }

  /// Recomputes the row totals and their running sums from values(); returns the total.
  float update();
  /// The total update() would return for values() as they are now, bit for bit, without storing
  /// anything: for a caller that needs the total to rewrite the masses before update().
  float sum() const;
  float total() const { return total_; }
  bool valid() const { return valid_total(total_); }
  /// Whether a distribution with this total is valid() (see above).
  static bool valid_total(float t) { return t >= std::numeric_limits<float>::min() && std::isfinite(t); }

  /// Probability of cell (x, y), or of the cell with row-major index i = y * w + x.
  float pmf(int i) const { return mass_[static_cast<std::size_t>(i)] * inv_total_; }
  float pmf(int x, int y) const { return pmf(y * w_ + x); }

  /// A row with u.y, then a cell of the row with u.x; u in [0,1)^2 (clamped).
  Sample sample(Point2 u) const;
  /// sample() in its two steps, for a caller that draws from many distributions at once and lets the
  /// cache misses of one step overlap before the next (render/oracle.cpp): the row for u.y (y and
  /// offset.y), then the cell of that row for u.x. sample_row(u.y) then sample_in_row(u.x) is sample(u).
  Sample sample_row(float uy) const;
  void sample_in_row(float ux, Sample* s) const;
  /// Starts loading the row search's data, or row y's masses, into the cache.
  void prefetch_rows() const {
    __builtin_prefetch(row_cdf_.data());
    __builtin_prefetch(row_sum_.data());
  }
  void prefetch_row(int y) const { detail::prefetch_floats(mass_.data() + static_cast<std::size_t>(y) * w_, w_); }
  /// The u that sample() maps to cell (x, y) and `offset`; inverse of sample() on cells with mass.
  Point2 invert(int x, int y, Point2 offset) const;

 private:
  int w_ = 0, h_ = 0;
  std::vector<float> mass_;     // padded_size() entries, w * h used
  std::vector<float> row_sum_;  // h: each row's total mass
  std::vector<float> row_cdf_;  // h: running sums of the row totals (the last is total_)
  template <class OnRow>
  float accumulate_rows(OnRow on_row) const;  // the running sum over the rows; on_row(r, total, run)
  template <int W, class OnRow>
  float accumulate_rows_of(OnRow on_row) const;
  float total_ = 0, inv_total_ = 0;
};

namespace detail {
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;
inline float clamp_unit(float u) { return std::min(std::max(u, 0.0f), kOneMinusEpsilon); }
}  // namespace detail

// Inline: the product sampler draws one sample per shading point right after update().
inline DiscreteDistribution2D::Sample DiscreteDistribution2D::sample(Point2 u) const {
  Sample s = sample_row(u.y);
  sample_in_row(u.x, &s);
  return s;
}

inline DiscreteDistribution2D::Sample DiscreteDistribution2D::sample_row(float u) const {
  const float uy = detail::clamp_unit(u) * total_;
  const float* rows = row_cdf_.data();
  Sample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(rows, rows + h_, uy) - rows, h_ - 1));
  while (s.y > 0 && !(row_sum_[s.y] > 0)) --s.y;  // rounding past the last row with mass
  const float row_start = s.y > 0 ? rows[s.y - 1] : 0.0f;
  const float row_mass = row_sum_[s.y];
  s.offset.y = row_mass > 0 ? detail::clamp_unit((uy - row_start) / row_mass) : 0.5f;
  return s;
}

inline void DiscreteDistribution2D::sample_in_row(float u, Sample* s) const {
  const float target = detail::clamp_unit(u) * row_sum_[s->y];
  const float* row = mass_.data() + static_cast<std::size_t>(s->y) * w_;
  // The first cell whose running sum exceeds the target; if rounding leaves the target at the row's
  // end, the last cell with mass. Cells without mass are never chosen.
  float run = 0, start = 0;
  s->x = -1;
  for (int x = 0; x < w_; ++x) {
    const float m = row[x];
    if (!(m > 0)) continue;
    s->x = x;
    start = run;
    run += m;
    if (run > target) break;
  }
  if (s->x < 0) {  // an empty row: only when the whole distribution is (not valid())
    s->x = 0;
    s->offset.x = 0.5f;
    return;
  }
  s->offset.x = detail::clamp_unit((target - start) / row[s->x]);
  s->pmf = row[s->x] * inv_total_;
}


/// A view of an n x n distribution over external storage: its masses (n^2, row-major) and their
/// normalized running sums in the layout build() writes: the n row ends first (the marginal, so the
/// row search reads contiguous memory), then each row's first n - 1 running sums.
class CumulativeDistribution2DView {
 public:
  using Sample = DiscreteDistribution2D::Sample;

  /// Writes the running sums of n x n masses (>= 0) into cdf (n^2 floats); returns the masses' total.
  /// A total of 0 writes uniform sums: such a distribution must never be chosen by a level above.
  static double build(const float* masses, int n, float* cdf);

  /// total: the masses' sum as build() returned it (0: every pmf is 0).
  CumulativeDistribution2DView(const float* masses, const float* cdf, float total, int n)
      : mass_(masses), cdf_(cdf), total_(total), n_(n) {}

  /// A row with u.y among the row ends, then a cell of the row with u.x; u in [0,1)^2 (clamped).
  Sample sample(Point2 u) const;
  /// Probability of cell (x, y).
  float pmf(int x, int y) const {
    return total_ > 0 ? mass_[static_cast<std::size_t>(y) * n_ + x] / total_ : 0.0f;
  }
  /// The u that sample() maps to cell (x, y) and `offset`.
  Point2 invert(int x, int y, Point2 offset) const;

 private:
  const float* mass_;
  const float* cdf_;
  float total_;
  int n_;
};

inline CumulativeDistribution2DView::Sample CumulativeDistribution2DView::sample(Point2 u) const {
  const float uy = detail::clamp_unit(u.y), ux = detail::clamp_unit(u.x);
  const int n = n_;
  // Each binary search would wait on one cache line after another; loading all of a search's lines
  // at once lets the misses overlap (the fine level is megabytes, mostly beyond L2). Up to 8 lines
  // each: a longer search touches only a few of its lines.
  constexpr int kMaxPrefetch = 128;  // floats: 8 cache lines
  const int span = std::min(n, kMaxPrefetch);
  detail::prefetch_floats(cdf_, span);
  Sample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(cdf_, cdf_ + n, uy) - cdf_, n - 1));
  detail::prefetch_floats(cdf_ + n + static_cast<std::size_t>(s.y) * (n - 1), std::min(n - 1, kMaxPrefetch));
  detail::prefetch_floats(mass_ + static_cast<std::size_t>(s.y) * n_, span);
  const float row_start = s.y > 0 ? cdf_[s.y - 1] : 0.0f;
  const float row_end = cdf_[s.y];
  const float row_mass = row_end - row_start;
  s.offset.y = row_mass > 0 ? detail::clamp_unit((uy - row_start) / row_mass) : 0.5f;
  const float target = row_start + ux * row_mass;
  const float* row = cdf_ + n + static_cast<std::size_t>(s.y) * (n - 1);  // entries 0 .. n-2
  s.x = static_cast<int>(std::upper_bound(row, row + (n - 1), target) - row);  // n - 1: the last column
  if (s.x == n - 1 && !(row_end > target)) {  // rounding at the row's end: the last column with mass
    while (s.x > 0 && (s.x == n - 1 ? row_end : row[s.x]) <= row[s.x - 1]) --s.x;
  }
  const float c0 = s.x > 0 ? row[s.x - 1] : row_start;
  const float c1 = s.x < n - 1 ? row[s.x] : row_end;
  const float mass = c1 - c0;
  s.offset.x = mass > 0 ? detail::clamp_unit((target - c0) / mass) : 0.5f;
  s.pmf = pmf(s.x, s.y);
  return s;
}

}  // namespace envpis
