// SPDX-License-Identifier: Apache-2.0
// Portals: planar convex quads (the windows of a room) through which the environment is seen from a
// shading point inside (issue 24; docs/portals.md has the design and the measurements).
//
// Portals holds up to kMaxPortals quads, validated on entry, and answers exactly whether the ray from
// a point p in direction d passes through any of them (ray-plane, then the quad's four edges).
//
// PortalView is that set seen from one shading point p, against an ImportanceTable's cells: per top
// cell c an estimate V[c] in [0, 1] of the fraction of the cell's directions that pass through a portal
// (and, on request, the same per sub-cell). From p, a convex quad subtends a spherical polygon: the
// directions on the inner side of the four planes through p and each edge. Each cell's bounding cone
// (axis a, half-angle b) is classified against those planes with one dot product each:
//   outside  some plane has a . n < -sin b    (no direction of the cone is on its inner side)
//   inside   every plane has a . n >= sin b   (every direction of the cone passes through the quad)
//   partial  otherwise.
// (A cell whose cone misses a bounding cone of the portal's directions is outside too. The top cells
// go through one vectorized pass for all portals, in the instruction set PortalViewOptions::simd names.)
// The rule every estimate keeps: V[c] = 0 exactly when the cell is outside every portal, so a
// direction where V is 0 provably misses every portal, and 1 when inside one. A partial cell gets
//   Cone (default)  the product over the four planes of the share of a ball cut by a plane at signed
//                   distance x = (a . n) / sin b, 1/2 + 3x/4 - x^3/4 (a smooth stand-in for the
//                   share of the cone's disk; no extra work beyond the dot products);
//   Grid            the share of a fixed K x K stratified grid of the cell's equal-area points whose
//                   directions pass through a portal (K^2 more edge tests per partial cell);
// both at least kMinPartial, so a portal smaller than a grid spacing still gets samples. Several
// portals add up, capped at 1. These are estimates: a sampler stays exact as long as sample() and
// pdf() use the same V, which they do (PortalEnvironmentSampler, ProductSampler with a view).
//
// Which point: the estimate is per shading point, the quads' spherical polygons change with p.
// Portals are one-sided (pbrt-v4's and Cycles' are too): a portal passes light inwards only, so a point
// on its outer side, or in its plane (edge-on, zero solid angle), leaves it out.
// Non-convex quads are rejected (their spherical polygon is not the intersection of the edge planes).
//
// Usage: one PortalView per thread (it owns O(T^2) scratch allocated once, like ProductSampler); per
// shading point prepare(p), then hand it to the sampler's prepare.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "envpis/common.h"
#include "envpis/importance_table.h"
#include "envpis/simd.h"

namespace envpis {

namespace detail {
struct Kernels;
}

/// A planar convex quad: its vertices in order around it, counter-clockwise seen from the environment
/// (outside the room), so that its normal (v1 - v0) x (v2 - v1) points out, towards the environment.
struct Quad {
  Vec3 v[4];
};

class Portals {
 public:
  static constexpr int kMaxPortals = 8;

  Portals() = default;
  /// Validates every quad (see add()); throws Error naming the first bad one.
  explicit Portals(const std::vector<Quad>& quads);
  /// Adds a quad. Throws Error (naming the quad's index) when a vertex is not finite, when the quad is
  /// degenerate (an edge or its area is zero relative to its size), not planar (a vertex farther than
  /// 1e-3 of its size from the plane of the others) or not convex, or when kMaxPortals are already held.
  void add(const Quad& quad);

  int size() const { return static_cast<int>(quads_.size()); }
  bool empty() const { return quads_.empty(); }
  const Quad& quad(int i) const { return quads_[static_cast<std::size_t>(i)]; }
  /// Unit normal of quad i (from its winding): it points out of the room.
  Vec3 normal(int i) const { return normals_[static_cast<std::size_t>(i)]; }

  /// Exact: whether the ray p + t d, t > 0, passes through quad i outwards (its edges count as inside).
  /// Portals are one-sided: a point on the environment's side of a quad's plane never passes it.
  bool passes(int i, Vec3 p, Vec3 d) const;
  /// Whether it passes through any quad.
  bool passes(Vec3 p, Vec3 d) const;

 private:
  std::vector<Quad> quads_;
  std::vector<Vec3> normals_;
};

/// How a partial cell's visible fraction is estimated (see above).
enum class PortalEstimate { Cone, Grid };
const char* to_string(PortalEstimate e);
PortalEstimate parse_portal_estimate(const std::string& s);  ///< "cone" | "grid"; throws Error otherwise

struct PortalViewOptions {
  PortalEstimate estimate = PortalEstimate::Cone;
  int grid = 4;  ///< K for PortalEstimate::Grid, 1..16
  Simd simd = Simd::Best;  ///< instruction set of the top cells' pass (envpis/simd.h)
};

class PortalView {
 public:
  /// The least V of a partial cell (see above).
  static constexpr float kMinPartial = 1.0f / 64.0f;

  /// Keeps a reference to the table (it must outlive the view) and a copy of the portals.
  PortalView(const ImportanceTable& table, const Portals& portals, const PortalViewOptions& options = {});

  /// Estimates V for shading point p. Returns visible(): false when p is not finite, when there are no
  /// portals, or when no cell is estimated visible (p outside the room facing away, every portal
  /// edge-on): a sampler prepared with such a view has no sample.
  bool prepare(Vec3 p);
  bool visible() const { return visible_; }
  Vec3 point() const { return p_; }

  /// V[c] of top cell c for the prepared point, in [0, 1]; cell_fractions() has T^2 of them (padded).
  float cell_fraction(int c) const { return v_[static_cast<std::size_t>(c)]; }
  const float* cell_fractions() const { return v_.data(); }
  /// Writes the S x S sub-cells' fractions of top cell c (row-major, S = table().subdivision()) into
  /// out; 0 everywhere when V[c] = 0, 1 when the cell is inside a portal. Returns whether any is > 0.
  bool subcell_fractions(int c, float* out) const;
  /// Exact, from the prepared point: whether direction d passes through a portal.
  bool passes(Vec3 d) const { return portals_.passes(p_, d); }

  const Portals& portals() const { return portals_; }
  const ImportanceTable& table() const { return *table_; }
  const PortalViewOptions& options() const { return options_; }

 private:
  // One portal from the prepared point: the unit normals of the planes through p and each edge,
  // oriented so that the quad's directions are on their positive side.
  struct Seen {
    float n[4][3];
    float g[3];        // a bounding cone of the quad's directions: axis, cos and sin of its half-angle
    float cos_p, sin_p;
    bool wide;         // wider than 90 degrees: no use as a bound
  };
  // Cones as padded arrays for the kernel (src/kernels.h, PortalCellArrays).
  struct ConeArrays {
    std::vector<float> ax, ay, az, inv_sin, out_thr, in_thr, cos, sin, big;
    void assign(std::size_t padded);
    void set(std::size_t i, const Cone& k);
  };
  static std::shared_ptr<const ConeArrays> subcell_arrays(const ImportanceTable& table, std::size_t stride);
  // Bit i set: cone not outside seen portal i; `inside`: inside one of them.
  unsigned classify(const Cone& cone, bool& inside) const;
  float grid_fraction(const Vec3* dirs, int count, unsigned mask) const;
  // The kernel's fractions of `count` cones of `a` from `offset` on (count a multiple of 16) into v and
  // full; whether any is positive.
  bool shares(const ConeArrays& a, std::size_t offset, int count, float* v, float* full) const;
  void cone_pass();
  void grid_pass();

  const ImportanceTable* table_;
  Portals portals_;
  PortalViewOptions options_;
  Vec3 p_;
  std::vector<Seen> seen_;  // the portals p sees (not edge-on)
  std::vector<float> sizes_;  // per portal: its longer diagonal (the scale of the edge-on test)
  std::vector<float> v_;    // V[c], padded like the table's top level
  ConeArrays top_;              // the top cells, padded like the table's top level
  // Every cell's sub-cells, sub_stride_ per cell (S > 1): a function of the grid alone, shared by
  // every view on a T x S grid (a product cache holds one view per slot).
  std::shared_ptr<const ConeArrays> sub_;
  std::size_t sub_stride_ = 0;  // S^2 rounded up to a multiple of 16 (<= 64)
  std::vector<float> full_;  // per cell: 1 when a portal holds its whole cone
  const detail::Kernels* kernels_;  // the instruction set options.simd names
  std::vector<Vec3> grid_dirs_;  // Grid: K^2 directions per top cell, cell-major
  bool visible_ = false;
};

}  // namespace envpis
