// SPDX-License-Identifier: Apache-2.0
// Environment-only sampling through portals: the baseline next to the product with portals (issue 24).
//
// For a shading point p (a PortalView prepared for it), the top cells weigh
//     W[c] = E[c] V[c]
// with E[c] the table's environment share and V[c] the view's estimate of the cell's visible fraction
// (envpis/portals.h). On a table with sub-cells the chosen cell's sub-cells weigh E[s | c] V[s] the
// same way (the environment's own shares when none of them is estimated visible, so a cell with
// W[c] > 0 always has a sub-cell to sample). Inside, the table's fine distribution. The density of w
// in sub-cell s of cell c is W[c] / sum W times the sub-cell level's probability times the fine
// density: pdf() returns exactly that, for MIS with BSDF sampling, since sample() and pdf() read the
// same weights. Where V[c] = 0 (provably no portal) the density is 0: BSDF samples carry those
// directions alone, and MIS stays unbiased.
//
// Invalid (sample() returns pdf 0, pdf() returns 0, never NaN): the view sees nothing (visible() is
// false), or the table is empty, or every visible cell has E[c] = 0 (a compensated table).
//
// Like ProductSampler: one per thread (O(T^2) scratch allocated once), prepare() per shading point,
// then any number of sample() / pdf(); the view must stay prepared for the same point meanwhile.
#pragma once

#include "envpis/discrete_distribution_2d.h"
#include "envpis/importance_table.h"
#include "envpis/portals.h"

namespace envpis {

class PortalEnvironmentSampler : private SubcellLevel {
 public:
  explicit PortalEnvironmentSampler(const ImportanceTable& table);

  /// Builds W for the point `view` was prepared for; keeps a pointer to `view`. Returns valid().
  bool prepare(const PortalView& view);
  bool valid() const { return valid_; }

  DirectionSample sample(Point2 u) const;
  float pdf(Vec3 wi) const;
  Point2 invert(Vec3 wi) const;

  /// Normalized probability of top cell c for the prepared point.
  float cell_probability(int c) const { return top_.pmf(c); }
  const DiscreteDistribution2D& top_level() const { return top_; }
  /// The sub-cell level of cell c: E[s | c] V[s], normalized (see above).
  const DiscreteDistribution2D& subcells(int c) const override;
  const ImportanceTable& table() const { return *table_; }

 private:
  const ImportanceTable* table_;
  const PortalView* view_ = nullptr;
  DiscreteDistribution2D top_;
  mutable DiscreteDistribution2D sub_;  // the last cell's sub-cell level
  mutable int sub_cell_ = -1;
  bool valid_ = false;
};

/// Cell c's sub-cell level through the portals into `out` (S x S): E[s | c] V[s], or the environment's
/// shares E[s | c] when no sub-cell is estimated visible. Returns whether the portals restricted it.
/// Shared by PortalEnvironmentSampler and ProductSampler (which multiplies its proxy in).
bool portal_subcell_shares(const ImportanceTable& table, const PortalView& view, int c, float* out);

}  // namespace envpis
