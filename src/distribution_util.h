// Internal: sampling a piecewise-constant 2D distribution stored as one row-major array of running
// sums normalized to end at 1 (the marginal over rows is read off the row ends, so no separate
// marginal table is stored).
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
/// in row-major order; `total` is the last entry (1 for a normalized table). Chooses a row with u.y
/// (from the row ends), then a column inside it with u.x: the sample keeps the 2D stratification of u.
inline Flat2DSample sample_flat2d(const float* cdf, int w, int h, Point2 u, float total = 1.0f) {
  const float uy = clamp_unit(u.y) * total, ux = clamp_unit(u.x);
  // Row: first r whose row end exceeds uy.
  int lo = 0, hi = h - 1;
  while (lo < hi) {
    const int mid = (lo + hi) >> 1;
    if (cdf[mid * w + w - 1] > uy) hi = mid;
    else lo = mid + 1;
  }
  Flat2DSample s;
  s.y = lo;
  const float row_start = s.y > 0 ? cdf[s.y * w - 1] : 0.0f;
  const float row_end = cdf[s.y * w + w - 1];
  const float row_mass = row_end - row_start;
  s.oy = row_mass > 0 ? clamp_unit((uy - row_start) / row_mass) : 0.5f;  // row_start <= uy < row_end
  // Column: first x in the row whose running sum exceeds the target.
  const float target = row_start + ux * row_mass;
  const float* row = cdf + s.y * w;
  const float* it = std::upper_bound(row, row + w, target);
  s.x = static_cast<int>(it - row);
  if (s.x >= w) {  // rounding put the target at the row's end: take the last column with mass
    s.x = w - 1;
    while (s.x > 0 && row[s.x] <= row[s.x - 1]) --s.x;
  }
  const float c0 = s.x > 0 ? row[s.x - 1] : row_start;
  const float mass = row[s.x] - c0;
  s.ox = mass > 0 ? clamp_unit((target - c0) / mass) : 0.5f;
  return s;
}

/// The same running sums stored so that both searches of a sample read contiguous memory: first the
/// h row ends (the marginal), then each row's other w - 1 entries. Same size as the row-major array.
inline void store_split2d(const float* cdf, int w, int h, float* out) {
  for (int y = 0; y < h; ++y) {
    out[y] = cdf[y * w + w - 1];
    for (int x = 0; x < w - 1; ++x) out[h + y * (w - 1) + x] = cdf[y * w + x];
  }
}

/// sample_flat2d() for the split layout of store_split2d().
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

/// A w x h table stored as running sums inside each row (`within`, w * h entries) and running sums of
/// the row totals (`rows`, h entries, the last being `total`): the row with u.y, the column with u.x.
inline Flat2DSample sample_rows2d(const float* rows, const float* within, int w, int h, Point2 u, float total) {
  const float uy = clamp_unit(u.y) * total, ux = clamp_unit(u.x);
  Flat2DSample s;
  s.y = static_cast<int>(std::min<long>(std::upper_bound(rows, rows + h, uy) - rows, h - 1));
  const float row_start = s.y > 0 ? rows[s.y - 1] : 0.0f;
  const float* row = within + static_cast<std::size_t>(s.y) * w;
  const float row_mass = row[w - 1];
  s.oy = row_mass > 0 ? clamp_unit((uy - row_start) / row_mass) : 0.5f;
  const float target = ux * row_mass;
  s.x = static_cast<int>(std::upper_bound(row, row + w, target) - row);
  if (s.x >= w) {  // rounding at the row's end: the last column with mass
    s.x = w - 1;
    while (s.x > 0 && row[s.x] <= row[s.x - 1]) --s.x;
  }
  const float c0 = s.x > 0 ? row[s.x - 1] : 0.0f;
  const float mass = row[s.x] - c0;
  s.ox = mass > 0 ? clamp_unit((target - c0) / mass) : 0.5f;
  return s;
}

}  // namespace envpis::detail
