// SPDX-License-Identifier: Apache-2.0
// Internal: the importance table's fine level made of a lat-long map's own texels
// (ImportanceTableOptions::fine_texels = FineTexels::Map).
//
// Every map texel belongs to one leaf (a sub-cell of the table, or its top cell when S = 1): the leaf
// whose part of the equal-area square holds the world direction of the texel's centre. A leaf is thus
// the union of whole map texels, a jagged version of its square cell. Inside a leaf a texel is chosen
// in proportion to importance x solid angle by one 1D distribution over the leaf's texels in row-major
// order, and the direction is uniform in solid angle inside the texel (uniform in azimuth and in
// cos theta). The density inside the leaf is importance(t) / W(leaf), constant over each map texel.
//
// Why: a light sample's weight L / pdf is then constant over each map texel under nearest look-ups
// (and close to it under bilinear ones), so where inside the texel a sample lands does not matter.
// With the equal-area fine level, table texels straddle the map's texel edges and the estimate jumps
// inside them, which no stratification of u removes (docs/cycles.md, "Why Cycles converged faster in
// the highlight").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "envpis/environment_map.h"
#include "fine_level.h"

namespace envpis::detail {

struct MapTexelOptions {
  float floor = 0;       ///< minimum importance relative to the mean importance per steradian
  float peak_ratio = 0;  ///< K (0: off): importance >= 1/K of the largest radiance eval reaches in the texel
  bool compensated = false;
  /// The map is read with bilinear look-ups (the peak bound applies; under nearest ones eval returns
  /// the texel's own value, which the importance already is).
  bool bilinear = true;
};

class MapTexelLevel {
 public:
  /// The level of a lat-long map cut into leaves x leaves cells of the equal-area square.
  MapTexelLevel(const EnvironmentMap& map, int leaves, const MapTexelOptions& options);

  /// Sum over the sphere of importance x solid angle; 0 for a black map (every leaf empty).
  double integral() const { return integral_; }
  /// Each leaf's importance x solid angle (row-major leaves of the equal-area square).
  const std::vector<double>& leaf_sums() const { return leaf_sum_; }
  /// Importance-weighted and plain sums of the texel centres' directions per leaf (for the moments).
  std::vector<DirectionSums> leaf_directions() const;

  struct Sample {
    Vec3 direction;    ///< world
    float density;     ///< solid-angle density inside the leaf, importance(t) / W(leaf)
    bool exact;        ///< the direction looks up the sampled texel again (density is pdf_in_leaf's)
    Point2 texture;    ///< the direction's lat-long coordinates (texture_of), computed for `exact`
  };
  /// A direction in leaf `leaf` (which must have a positive sum) from u in [0,1)^2.
  Sample sample(int leaf, Point2 u) const;

  struct Located {
    int leaf;       ///< the leaf the direction's texel belongs to
    float density;  ///< solid-angle density inside that leaf (0 when the leaf is empty)
  };
  /// Where world direction d is: its texel's leaf and the density there.
  Located locate(Vec3 d) const { return locate_texture(texture_of(d)); }
  /// The same for the direction whose lat-long coordinates are `uv` (texture_of(d)).
  Located locate_texture(Point2 uv) const;
  /// Starts fetching what locate_texture(uv) reads.
  void prefetch(Point2 uv) const { __builtin_prefetch(&at_[static_cast<std::size_t>(texel_at(uv))]); }
  /// The lat-long coordinates world direction d reads the map at: EnvironmentMap::texture_coord(d).
  Point2 texture_of(Vec3 world) const { return direction_to_latlong(to_map_ * world); }
  /// The u that sample(locate(d).leaf, u) maps to d (up to round-off).
  Point2 invert(Vec3 d) const;

  int width() const { return w_; }
  int height() const { return h_; }
  /// Texel (x, y)'s importance.
  float importance(int x, int y) const { return imp_[static_cast<std::size_t>(y) * w_ + x]; }
  std::size_t bytes_used() const;

 private:
  // What a sample or a look-up reads together sits together: one cache line per texel instead of
  // one per array (a light sample's and a pdf's texel are rarely in cache on a large map).
  struct TexelLeaf {
    float density;       // importance / W(leaf): the solid-angle density inside its leaf
    std::uint32_t leaf;  // the leaf the texel belongs to
  };
  struct Entry {
    float cdf;            // running sum inside the leaf, normalized, the last 1
    std::uint32_t texel;  // row-major texel index
  };
  void compute_importance(const MapTexelOptions& options);
  void assign_leaves(int leaves);
  void build_leaf_cdfs();
  void build_guides();
  const Entry* find(int leaf, float u) const;  // the entry whose cdf interval holds u
  int texel_at(Point2 uv) const;  // row-major index of the texel a look-up at lat-long uv reads
  float row_solid_angle(int y) const { return row_sr_[static_cast<std::size_t>(y)]; }

  Mat3 to_map_, to_world_;  // the map's (the table must not keep a reference to the map)
  int w_ = 0, h_ = 0, leaves_ = 0;
  double integral_ = 0;
  std::vector<float> row_sr_;           // h: solid angle of one texel of each row
  // Per row boundary, 1 - cos theta and 1 + cos theta: a texel's direction is computed from the one
  // that is small in its half, since near a pole cos theta is within round-off of +-1 across a row.
  std::vector<float> row_qn_, row_qs_;  // h + 1 each
  std::vector<float> imp_;              // w h: importance per texel
  std::vector<TexelLeaf> at_;           // w h: each texel's leaf and density
  std::vector<std::uint32_t> start_;    // leaves^2 + 1: each leaf's first entry
  std::vector<Entry> entry_;            // w h, leaf-major, row-major inside a leaf
  // Per leaf of n entries, g + 1 = n / kGuideStride + 2 indices: guide k is the first entry whose cdf
  // has key(cdf) >= k (key(x) = min(g - 1, floor(x g))), so the entry a u looks for lies between
  // guides key(u) and key(u) + 1: a search of a few entries instead of log2(n) scattered reads.
  std::vector<std::uint32_t> guide_;        // the leaves' guides, concatenated
  std::vector<std::uint32_t> guide_start_;  // leaves^2 + 1: each leaf's first guide
  std::vector<double> leaf_sum_;        // leaves^2
  std::vector<float> inv_leaf_sum_;     // leaves^2 (0 for an empty leaf)
};

}  // namespace envpis::detail
