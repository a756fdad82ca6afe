// The two-level importance table of an environment map (Conty Estevez & Lecocq 2018, section 2).
//
// Both levels live on the equal-area square, so every cell of a level subtends the same solid angle.
//   top level:  T x T cells (T = 12 by default). Per cell: its probability E[c] (share of the map's
//               importance), and a cone (axis, half-angle) that contains every direction of the cell.
//   fine level: N x N texels, N = T * F. Each top cell owns the F x F texels inside it and its own
//               piecewise-constant 2D distribution over them.
//
// Fine resolution rule: N is the smallest multiple of T with N >= 2 sqrt(texel count), i.e. four table
// texels per map texel (1024x512 -> N = 1452, F = 121), but no more than 2904 unless the map alone
// has more texels (then N^2 >= texel count: 4096x2048 -> 2904). ImportanceTableOptions::fine_resolution
// overrides it (rounded up to a multiple of T). Why twice: table texels never line up with a lat-long
// map's texels, so at equal resolution each table texel mixes several map texels and its importance
// misstates what eval returns inside it; at twice the resolution sunrise's relMSE on fig1 halves
// (BENCHMARKS.md).
//
// Importance of a fine texel: the average of the RGB channels of the radiance, averaged over the
// texel by stratified bilinear look-ups (or, where map texels are much smaller than table texels, by
// splatting their energy), then raised to at least 1/K of the largest channel-average radiance that
// EnvironmentMap::eval can return anywhere inside the texel (K = ImportanceTableOptions::peak_ratio),
// and to at least `floor` times the mean importance.
//
// Guarantee (uncompensated tables, K > 0): for every direction d,
//     eval(d).average() / pdf(d) <= K * integral(),
// so no environment light sample weighs more than K perfect ones: a small bright sun that the average
// misses cannot make a firefly. The price is that a source much smaller than a table texel draws more
// samples than its energy share (at most its bounding texels' area times its radiance / K).
// The floor keeps the density positive in every direction, so environment-only sampling is unbiased
// wherever radiance is positive.
//
// Memory: N^2 importance values + N^2 cumulative values (floats) + a few floats per top cell: no more
// than a standard single-level 2D table (values + conditional CDFs + marginal) over N^2 texels, plus
// O(T^2). The table is immutable after construction and safe to share between threads.
#pragma once

#include <cstddef>
#include <vector>

#include "envpis/common.h"
#include "envpis/environment_map.h"

namespace envpis {

struct ImportanceTableOptions {
  int top_resolution = 12;  ///< T, 1..256
  int fine_resolution = 0;  ///< N; 0 = derived from the map's texel count (see above)
  float floor = 1e-4f;      ///< minimum texel importance, relative to the mean (0 disables; < 1)
  /// K: every texel's importance is at least 1/K of the largest radiance (channel average) the map's
  /// bilinear reconstruction reaches inside the texel, so no light sample weighs more than K times
  /// the map's integral (see the guarantee above). 0 turns the bound off; otherwise in [1, 1e6].
  float peak_ratio = 8.0f;
  /// MIS-compensated importance (Karlik et al. 2019): max(0, importance - mean), no floor. Only for use
  /// with MIS next to BSDF sampling: its density is zero wherever the map is darker than its mean.
  /// A constant map falls back to the uncompensated table.
  bool compensated = false;
};

/// Throws Error naming the first invalid option (what the ImportanceTable constructor checks), so
/// callers can reject options before any map is loaded.
void validate(const ImportanceTableOptions& options);

/// A bounding cone: every direction d of the cell has dot(d, axis) >= cos_half_angle.
struct Cone {
  Vec3 axis;
  float cos_half_angle = -1;
  float sin_half_angle = 0;
};

class ImportanceTable {
 public:
  /// Builds the table (in parallel with TBB). Throws Error for invalid options.
  /// An all-black map builds an empty() table: sample() then returns no sample and pdf() is 0;
  /// renderers should fall back to BSDF sampling (the environment contributes nothing anyway).
  explicit ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options = {});

  int top_resolution() const { return T_; }   ///< T
  int cell_resolution() const { return F_; }  ///< F: fine texels per top cell along one axis
  int fine_resolution() const { return N_; }  ///< N = T * F
  int cell_count() const { return T_ * T_; }
  bool empty() const { return empty_; }
  /// Sum over the sphere of the importance (average RGB radiance integrated over solid angle).
  double integral() const { return integral_; }

  /// Environment-only importance sampling: direction with probability proportional to importance.
  DirectionSample sample(Point2 u) const;
  /// Density (solid angle) of sample() at direction d. 0 for an invalid d or an empty table.
  float pdf(Vec3 d) const;

  /// Top cell index (y * T + x) that contains equal-area point p / direction d.
  int cell_of(Point2 p) const;
  int cell_of_direction(Vec3 d) const;
  /// Probability E[c] of top cell c (sums to 1 over the cells, all 0 when empty()).
  float cell_probability(int c) const { return cell_prob_[c]; }
  const Cone& cell_cone(int c) const { return cones_[c]; }
  /// Importance of fine texel (x, y), 0 <= x, y < N (equal-area square, y down).
  float importance(int x, int y) const;

  /// Bytes held by the table.
  std::size_t bytes_used() const;
  /// Bytes a standard single-level 2D piecewise-constant distribution over the same N^2 texels holds
  /// (values, conditional CDFs with N+1 entries per row, marginal values and CDF): for comparison.
  std::size_t single_level_bytes() const;
  /// Wall seconds the build took.
  double build_seconds() const { return build_seconds_; }

  // ---- for ProductSampler (and users building their own top-level distributions) ----
  /// Samples the fine distribution of top cell c with u in [0,1)^2; returns the equal-area point and
  /// sets *pdf_in_cell to the density inside the cell (over the cell's area, the cell having area 1).
  /// *interior (if given) tells whether the point is far enough inside its texel (2% of a texel) that
  /// the direction it maps to maps back into the same texel: then *pdf_in_cell equals
  /// pdf_in_cell(c, equal_area_sphere_to_square(direction)) exactly, and callers can skip that.
  Point2 sample_in_cell(int c, Point2 u, float* pdf_in_cell, bool* interior = nullptr) const;
  /// Density of the fine distribution of cell c at equal-area point p, normalized over the cell's area.
  float pdf_in_cell(int c, Point2 p) const;
  /// Structure-of-arrays cone and probability data, padded with zero cells to a multiple of 16.
  const float* soa_axis_x() const { return soa_[0].data(); }
  const float* soa_axis_y() const { return soa_[1].data(); }
  const float* soa_axis_z() const { return soa_[2].data(); }
  const float* soa_cos() const { return soa_[3].data(); }
  const float* soa_sin() const { return soa_[4].data(); }
  const float* soa_prob() const { return soa_[5].data(); }
  int padded_cell_count() const { return padded_; }

 private:
  void build_importance(const EnvironmentMap& map, float floor, float peak_ratio, bool compensated);
  void build_cells();
  void build_cones();
  std::size_t texel_index(int x, int y) const;  // index into func_/cdf_ (cell-major layout)

  int T_ = 12, F_ = 1, N_ = 12, padded_ = 16;
  bool empty_ = true;
  double integral_ = 0;
  double build_seconds_ = 0;
  std::vector<float> func_;  // N^2 importance values, laid out cell by cell, row-major inside a cell
  std::vector<float> cdf_;   // N^2 running sums inside each cell (row-major), normalized to end at 1
  std::vector<float> cell_sum_;   // per cell: sum of func_ over the cell
  std::vector<float> cell_prob_;  // per cell: E[c]
  std::vector<float> top_row_sum_;  // T: row totals of E[c], for environment-only sampling
  std::vector<float> top_row_cdf_;  // T: their running sums
  std::vector<Cone> cones_;
  std::vector<float> soa_[6];
};

}  // namespace envpis
