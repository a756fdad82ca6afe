// Internal: sampling piecewise-constant 2D distributions in two layouts:
//   split     running sums normalized to end at 1, row ends first (the fine tables, built once);
//   row scan  masses with row totals and their running sums (the top levels: the product sampler
//             rebuilds its per shading point, so it writes no per-cell running sums).
#pragma once

#include <algorithm>

#include "envpis/common.h"

namespace envpis::detail {

constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

inline float clamp_unit(float u) { return std::min(std::max(u, 0.0f), kOneMinusEpsilon); }

struct Flat2DSample {
  int x = 0, y = 0;      ///< chosen cell
  float ox = 0, oy = 0;  ///< continuous offset inside it, [0,1)
};

/// `cdf` has w * h entries: cdf[y * w + x] = sum of the masses of cells before and including (x, y)
/// in row-major order, normalized to end at 1. Stored so that both searches of a sample read
/// contiguous memory: first the h row ends (the marginal), then each row's other w - 1 entries.
inline void store_split2d(const float* cdf, int w, int h, float* out) {
  for (int y = 0; y < h; ++y) {
    out[y] = cdf[y * w + w - 1];
    for (int x = 0; x < w - 1; ++x) out[h + y * (w - 1) + x] = cdf[y * w + x];
  }
}

/// A row with u.y, then a column inside it with u.x, for the layout of store_split2d(): the sample
/// keeps the 2D stratification of u.
inline Flat2DSample sample_split2d(const float* split, int w, int h, Point2 u) {
  const float uy = clamp_unit(u.y), ux = clamp_unit(u.x);
  Flat2DSample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(split, split + h, uy) - split, h - 1));
  const float row_start = s.y > 0 ? split[s.y - 1] : 0.0f;
  const float row_end = split[s.y];
  const float row_mass = row_end - row_start;
  s.oy = row_mass > 0 ? clamp_unit((uy - row_start) / row_mass) : 0.5f;
  const float target = row_start + ux * row_mass;
  const float* row = split + h + static_cast<std::size_t>(s.y) * (w - 1);  // entries 0 .. w-2
  s.x = static_cast<int>(std::upper_bound(row, row + (w - 1), target) - row);  // w - 1: the last column
  if (s.x == w - 1 && !(row_end > target)) {  // rounding at the row's end: last column with mass
    while (s.x > 0 && (s.x == w - 1 ? row_end : row[s.x]) <= row[s.x - 1]) --s.x;
  }
  const float c0 = s.x > 0 ? row[s.x - 1] : row_start;
  const float c1 = s.x < w - 1 ? row[s.x] : row_end;
  const float mass = c1 - c0;
  s.ox = mass > 0 ? clamp_unit((target - c0) / mass) : 0.5f;
  return s;
}

/// The row totals of a w x h table of masses (row-major) and their running sums, the layout
/// sample_row_scan() reads; returns the total. Four partial sums per row keep the adds independent
/// (the product sampler calls this per shading point).
inline float store_row_sums(const float* mass, int w, int h, float* row_sum, float* row_cdf) {
  float run = 0;
  if (w == 12) {  // the default top level: the same sums without loop control (25 ns less per
                  // prepare + sample on the benchmark machine, BENCHMARKS.md)
    for (int r = 0; r < h; ++r) {
      const float* row = mass + static_cast<std::size_t>(r) * 12;
      const float a0 = (row[0] + row[4]) + row[8], a1 = (row[1] + row[5]) + row[9];
      const float a2 = (row[2] + row[6]) + row[10], a3 = (row[3] + row[7]) + row[11];
      row_sum[r] = (a0 + a1) + (a2 + a3);
      row_cdf[r] = run += row_sum[r];
    }
    return run;
  }
  for (int r = 0; r < h; ++r) {
    const float* row = mass + static_cast<std::size_t>(r) * w;
    float a0 = 0, a1 = 0, a2 = 0, a3 = 0;
    int k = 0;
    for (; k + 4 <= w; k += 4) {
      a0 += row[k];
      a1 += row[k + 1];
      a2 += row[k + 2];
      a3 += row[k + 3];
    }
    for (; k < w; ++k) a0 += row[k];
    row_sum[r] = (a0 + a1) + (a2 + a3);
    row_cdf[r] = run += row_sum[r];
  }
  return run;
}

/// A w x h table of masses `mass` (row-major) with its row totals `row_sum` and their running sums
/// `rows` (h entries, the last being `total`): the row with u.y (binary search), then the column with
/// u.x by a linear scan of that row's masses (no per-cell running sums are needed).
inline Flat2DSample sample_row_scan(const float* rows, const float* row_sum, const float* mass, int w, int h, Point2 u,
                                    float total) {
  const float uy = clamp_unit(u.y) * total, ux = clamp_unit(u.x);
  Flat2DSample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(rows, rows + h, uy) - rows, h - 1));
  while (s.y > 0 && !(row_sum[s.y] > 0)) --s.y;  // rounding past the last row with mass
  const float row_start = s.y > 0 ? rows[s.y - 1] : 0.0f;
  const float row_mass = row_sum[s.y];
  s.oy = row_mass > 0 ? clamp_unit((uy - row_start) / row_mass) : 0.5f;
  const float target = ux * row_mass;
  const float* row = mass + static_cast<std::size_t>(s.y) * w;
  // The first column whose running sum exceeds the target; if rounding leaves the target at the
  // row's end, the last column with mass. Columns without mass are never chosen.
  float c0 = 0, start = 0;
  s.x = -1;
  for (int x = 0; x < w; ++x) {
    const float m = row[x];
    if (!(m > 0)) continue;
    s.x = x;
    start = c0;
    c0 += m;
    if (c0 > target) break;
  }
  if (s.x < 0) {  // an empty row (only when the whole table is empty): any cell, centred
    s.x = 0;
    s.ox = 0.5f;
    return s;
  }
  s.ox = clamp_unit((target - start) / row[s.x]);
  return s;
}

}  // namespace envpis::detail
