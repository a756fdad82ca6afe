// SPDX-License-Identifier: Apache-2.0
// The two-level importance table of an environment map (Conty Estevez & Lecocq 2018, section 2).
//
// Both levels live on the equal-area square, so every cell of a level subtends the same solid angle.
//   top level:  T x T cells (T = 12 by default). Per cell: its probability E[c] (share of the map's
//               importance), a cone (axis, half-angle) that contains every direction of the cell, and
//               the cell's importance-weighted mean direction and spread (for the product sampler's
//               CellEstimate::Moments; the same per sub-cell).
//   sub-cells:  each top cell is cut into S x S sub-cells (S = 1 by default: the paper's two levels).
//               Per sub-cell: its share of its top cell's importance and a bounding cone, which a
//               refined sampler (ProductSampler with refine) weights again per shading point.
//   fine level: N x N texels, N = T * F, F a multiple of S. Each sub-cell owns the F/S x F/S texels
//               inside it and its own piecewise-constant 2D distribution over them.
//
// Sampling goes down the levels with one u: a top cell from a T x T distribution (the environment's
// own, or a product's), a sub-cell from an S x S distribution for that cell (SubcellLevel: again the
// environment's own, or a product's), a texel, a point. Each level hands the remainder of u to the
// next, so stratified u stay stratified, and the density is the product of the levels' probabilities.
//
// Fine resolution rule: N is the smallest multiple of T S with N >= 2 sqrt(texel count), i.e. four table
// texels per map texel (1024x512 -> N = 1452, F = 121), but no more than 2904 unless the map alone
// has more texels (then N^2 >= texel count: 4096x2048 -> 2904). ImportanceTableOptions::fine_resolution
// overrides it (rounded up to a multiple of T S). Why twice: table texels never line up with a lat-long
// map's texels, so at equal resolution each table texel mixes several map texels and its importance
// misstates what eval returns inside it (docs/decisions.md, "A fine table twice the map's resolution",
// has the measurement).
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
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "envpis/common.h"
#include "envpis/discrete_distribution_2d.h"
#include "envpis/environment_map.h"

namespace envpis {

namespace detail {
class FineLevel;
class MapTexelLevel;
struct CellCones;
struct DirectionSums;
}

/// What the fine level's texels are.
enum class FineTexels {
  EqualArea,  ///< N x N equal-area texels (the rule above); any map layout
  Map,        ///< the lat-long map's own texels (lat-long maps only; see below)
  Auto,       ///< Map for a lat-long map read with nearest look-ups, EqualArea otherwise
};

/// The texels a table built with `requested` over `map` uses (resolves Auto; never returns Auto).
/// Why Auto picks EqualArea under bilinear look-ups: there the map's texels need a peak bound over
/// their neighbourhood and a light sample's weight varies inside each texel, and fig1 measured every
/// strategy's error 1.2-1.5x higher than with the finer equal-area texels (BENCHMARKS.md, fig1 at
/// today's defaults); under nearest look-ups a sample's weight is constant per map texel, which is
/// what the sun's highlight needs (docs/cycles.md, "The fix").
FineTexels resolve_fine_texels(FineTexels requested, const EnvironmentMap& map);

/// Parses "equal-area", "map" or "auto"; throws Error otherwise.
FineTexels parse_fine_texels(const std::string& s);
const char* to_string(FineTexels f);

struct ImportanceTableOptions {
  int top_resolution = 12;  ///< T, 1..256
  /// S: sub-cells per top cell along each axis, 1..8 (T S <= 1024). 1: the paper's two levels; a
  /// refined ProductSampler needs S > 1.
  int subdivision = 1;
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
  /// FineTexels::Map: the fine level is the lat-long map's own texels. Each map texel belongs to the
  /// sub-cell (or top cell) that holds its centre, so cells are unions of whole map texels; inside a
  /// cell a texel is chosen in proportion to importance x solid angle and the direction is uniform in
  /// solid angle inside it. The density is then constant over each map texel, so under nearest
  /// look-ups a light sample's weight does not depend on where inside the texel it lands (which u
  /// cannot stratify); see docs/cycles.md. Importance is the texel's channel average (raised by the
  /// peak bound to 1/K of its 3 x 3 neighbourhood's largest under bilinear look-ups), floored or
  /// compensated as above. fine_resolution() is then 0 and importance(x, y) refers to map texels.
  FineTexels fine_texels = FineTexels::EqualArea;
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

/// The second level of a three-level sample: for each top cell c, a distribution over its S x S
/// sub-cells (row-major, sub-cell (x, y) of cell c). ImportanceTable::subcells(c) is the environment's.
class SubcellLevel {
 public:
  virtual ~SubcellLevel() = default;
  /// Cell c's sub-cell distribution, S x S. Only called for cells of positive top-level probability;
  /// it must be valid() then. The reference may be to scratch that the next call overwrites.
  virtual const DiscreteDistribution2D& subcells(int c) const = 0;
};

class ImportanceTable;
namespace detail {
struct CellArrays;
CellArrays cell_arrays(const ImportanceTable& table);  // the SIMD kernels' view (src/kernels.h)
CellArrays subcell_arrays(const ImportanceTable& table, int c);  // the same for top cell c's sub-cells
}  // namespace detail

class ImportanceTable {
 public:
  /// Builds the table (in parallel when the library has TBB). Throws Error for invalid options.
  /// An all-black map builds an empty() table: sample() then returns no sample and pdf() is 0;
  /// renderers should fall back to BSDF sampling (the environment contributes nothing anyway).
  explicit ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options = {});
  /// Tables of one map for several options (e.g. a plain and a compensated one), built together and in
  /// parallel: tables whose fine level is the same equal-area grid with the same peak ratio share the
  /// map's gather and peak bound, the costliest part of a build; each then applies its own floor or
  /// compensation. Every table is bit for bit the one its options build alone. Throws as the
  /// constructor does.
  static std::vector<std::shared_ptr<const ImportanceTable>> build_together(
      const EnvironmentMap& map, const std::vector<ImportanceTableOptions>& options);

  int top_resolution() const { return T_; }   ///< T
  int subdivision() const { return S_; }      ///< S: sub-cells per top cell along one axis
  int cell_resolution() const { return F_; }  ///< F: fine texels per top cell along one axis
  int fine_resolution() const { return N_; }  ///< N = T * F (0 when fine_texels() is Map)
  /// The fine level's texels: EqualArea or Map (never Auto).
  FineTexels fine_texels() const { return map_texels_ ? FineTexels::Map : FineTexels::EqualArea; }
  int cell_count() const { return T_ * T_; }
  bool empty() const { return empty_; }
  /// Sum over the sphere of the importance (average RGB radiance integrated over solid angle).
  double integral() const { return integral_; }

  /// Environment-only importance sampling: direction with probability proportional to importance.
  DirectionSample sample(Point2 u) const { return sample(top_, u); }
  /// Density (solid angle) of sample() at direction d. 0 for an invalid d or an empty table.
  float pdf(Vec3 d) const { return pdf(top_, d); }
  /// pdf(d), given `texture` = EnvironmentMap::texture_coord(d) of the map the table was built from: a
  /// table on the map's own texels (FineTexels::Map) reads d's texel from it instead of looking d up
  /// again; NaN: looked up from d. Other tables ignore it. A renderer that also needs the radiance of
  /// d computes the coordinate once (eval_texture(texture) is eval(d)). sample() returns the
  /// coordinate of its direction in DirectionSample::texture when it computed it.
  float pdf(Vec3 d, Point2 texture) const { return pdf(top_, d, texture); }
  /// Starts fetching what pdf(d, texture) reads at `texture` (as there) into the cache, for a caller
  /// that asks later. A hint: it changes no result (and does nothing for the equal-area fine level).
  void prefetch(Point2 texture) const;
  /// pdf(d) for d = equal_area_square_to_sphere(p), given the equal-area point p: an equal-area table
  /// locates p itself instead of mapping d back to the square (the same value but within round-off of
  /// a texel's edge). For callers that walk the square, as a quadrature over its texels does.
  float pdf_square(Point2 p) const { return pdf_square(top_, p); }
  /// pdf_square() anywhere in fine texel (x, y) (see pdf_texel(top, x, y)).
  float pdf_texel(int x, int y) const { return pdf_texel(top_, x, y); }
  /// The u that sample() maps to direction d (up to round-off), e.g. to test stratification.
  Point2 invert(Vec3 d) const { return invert(top_, d); }

  /// Sampling with any top level over this table's T x T cells (the product sampler's, a renderer's
  /// own): the cell from `top` with u, a sub-cell from `sub` (nullptr: the environment's own
  /// subcells()) with u's remainder, then a fine texel of that sub-cell with what remains. The density
  /// of a direction d in sub-cell s of cell c is top.pmf(c) sub.pmf(s) times the sub-cell's fine
  /// density, in solid angle (solid_angle_pdf). `top` must be T x T; an invalid `top` or an empty
  /// table gives pdf 0.
  DirectionSample sample(const DiscreteDistribution2D& top, Point2 u, const SubcellLevel* sub = nullptr) const;
  float pdf(const DiscreteDistribution2D& top, Vec3 d, const SubcellLevel* sub = nullptr) const;
  /// The same with d's texture coordinate (see pdf(d, texture)).
  float pdf(const DiscreteDistribution2D& top, Vec3 d, Point2 texture, const SubcellLevel* sub = nullptr) const;
  /// The same at the direction of equal-area point p (see pdf_square(p)).
  float pdf_square(const DiscreteDistribution2D& top, Point2 p, const SubcellLevel* sub = nullptr) const;
  /// pdf_square() anywhere in fine texel (x, y) of the equal-area grid (0 <= x, y < fine_resolution()),
  /// where the density is constant, without locating a point: for a quadrature over the texels.
  /// 0 outside the grid and for tables with the map's own texels (FineTexels::Map).
  float pdf_texel(const DiscreteDistribution2D& top, int x, int y, const SubcellLevel* sub = nullptr) const;
  Point2 invert(const DiscreteDistribution2D& top, Vec3 d, const SubcellLevel* sub = nullptr) const;
  /// The environment's own top level: cell (x, y) has probability E[c], c = y * T + x.
  const DiscreteDistribution2D& top_level() const { return top_; }

  /// The environment's distribution over the S x S sub-cells of top cell c (their shares of E[c]).
  /// (S = 1: one sub-cell, the cell itself, of probability 1.)
  const DiscreteDistribution2D& subcells(int c) const {
    return S_ > 1 ? env_sub_[static_cast<std::size_t>(c)] : whole_cell_;
  }
  /// Bounding cone of sub-cell s (row-major in its cell, 0 <= s < S^2) of top cell c.
  const Cone& subcell_cone(int c, int s) const {
    return S_ > 1 ? sub_cones_[static_cast<std::size_t>(c) * S_ * S_ + s] : cones_[static_cast<std::size_t>(c)];
  }

  /// Top cell index (y * T + x) that contains equal-area point p / direction d.
  int cell_of(Point2 p) const;
  int cell_of_direction(Vec3 d) const;
  /// Probability E[c] of top cell c (sums to 1 over the cells, all 0 when empty()).
  float cell_probability(int c) const { return top_.pmf(c); }
  const Cone& cell_cone(int c) const { return cones_[c]; }
  /// Importance of fine texel (x, y), 0 <= x, y < N (equal-area square, y down); for a Map table, of
  /// map texel (x, y), 0 <= x < width, 0 <= y < height.
  float importance(int x, int y) const;
  /// The grid importance(x, y) reads: N x N, or the map's width x height for a Map table.
  int importance_width() const;
  int importance_height() const;
  /// Density of the environment's distribution inside cell c (sub-cell, then fine) at equal-area
  /// point p, normalized over the cell's area.
  float pdf_in_cell(int c, Point2 p) const;
  /// Solid-angle density of a direction in a cell of probability cell_pmf whose density inside the
  /// cell (over the cell's area) is pdf_in_cell: a top cell covers 4 pi / T^2 steradians.
  float solid_angle_pdf(float cell_pmf, float pdf_in_cell) const;

  /// Bytes held by the table.
  std::size_t bytes_used() const;
  /// Bytes a standard single-level 2D piecewise-constant distribution over the same N^2 texels holds
  /// (values, conditional CDFs with N+1 entries per row, marginal values and CDF): for comparison.
  std::size_t single_level_bytes() const;
  /// Wall seconds the build took.
  double build_seconds() const { return build_seconds_; }

 private:
  ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options, const detail::FineLevel* gathered);
  friend detail::CellArrays detail::cell_arrays(const ImportanceTable& table);
  friend detail::CellArrays detail::subcell_arrays(const ImportanceTable& table, int c);
  void build_levels(const std::vector<double>& subcell_sums);
  void build_cones();
  void build_moments(const std::vector<detail::DirectionSums>& leaf);
  void cell_and_sub(int leaf, int& c, int& s) const;  // the top cell and sub-cell of a leaf
  struct LeafIndex {
    std::int32_t cell, sub;
  };
  std::vector<LeafIndex> leaf_index_;  // per leaf (sub-cell of the T S x T S grid): cell_and_sub's answer
  std::vector<std::int32_t> axis_leaf_;  // equal-area: per fine texel column (= row), its leaf column
  struct Located {  // where an equal-area point is: top cell, sub-cell in it, fine-level cell,
    int cell, sub, leaf, tx, ty;  // texel (tx, ty) in the fine-level cell
  };
  Located locate(Point2 p) const;
  Located locate_texel(int x, int y) const;  // fine texel (x, y) of the equal-area grid
  float pdf_located(const DiscreteDistribution2D& top, const Located& at, const SubcellLevel* sub) const;

  int T_ = 12, S_ = 1, F_ = 1, N_ = 12;
  bool empty_ = true;
  double integral_ = 0;
  double build_seconds_ = 0;
  std::shared_ptr<const detail::FineLevel> fine_;  // immutable: copies of the table share it
  std::shared_ptr<const detail::MapTexelLevel> map_texels_;  // instead of fine_ for FineTexels::Map
  DiscreteDistribution2D top_;
  std::vector<DiscreteDistribution2D> env_sub_;  // T^2 of S x S (empty when S = 1)
  DiscreteDistribution2D whole_cell_;            // S = 1: the one sub-cell
  // The cells' cones depend on the grid alone: shared by the tables on it (src/cell_cones.h).
  std::shared_ptr<const detail::CellCones> cell_cones_;
  const Cone* cones_ = nullptr;      // T^2, in cell_cones_
  const Cone* sub_cones_ = nullptr;  // T^2 S^2, cell-major (none when S = 1), in cell_cones_
  // Cone axis x, y, z, cos, sin, E[c], then the importance-weighted mean direction x, y, z and its
  // spread (detail::CellArrays); padded like top_.values().
  std::vector<float> soa_[10];
  std::vector<float> sub_soa_[10];  // the same per sub-cell (share of its cell), sub_stride_ per cell
  int sub_stride_ = 0;
};

}  // namespace envpis
