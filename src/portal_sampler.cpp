// SPDX-License-Identifier: Apache-2.0
#include "envpis/portal_sampler.h"

#include <algorithm>

namespace envpis {

bool portal_subcell_shares(const ImportanceTable& table, const PortalView& view, int c, float* out) {
  const int n = table.subdivision() * table.subdivision();
  const float* e = table.subcells(c).values();
  float v[64];
  bool any = false;
  if (view.subcell_fractions(c, v))
    for (int s = 0; s < n; ++s) {
      out[s] = e[s] * v[s];
      any = any || out[s] > 0.0f;
    }
  if (!any) std::copy(e, e + n, out);  // nothing estimated visible (or visible but black): the cell's own
  return any;
}

PortalEnvironmentSampler::PortalEnvironmentSampler(const ImportanceTable& table)
    : table_(&table),
      top_(table.top_resolution(), table.top_resolution()),
      sub_(table.subdivision(), table.subdivision()) {}

bool PortalEnvironmentSampler::prepare(const PortalView& view) {
  valid_ = false;
  sub_cell_ = -1;
  view_ = &view;
  if (table_->empty() || !view.visible() || &view.table() != table_) return false;
  const int cells = table_->cell_count();
  const float* e = table_->top_level().values();
  const float* v = view.cell_fractions();
  float* w = top_.values();
  for (int c = 0; c < cells; ++c) w[c] = e[c] * v[c];
  top_.update();
  valid_ = top_.valid();
  return valid_;
}

const DiscreteDistribution2D& PortalEnvironmentSampler::subcells(int c) const {
  if (c != sub_cell_) {  // one cell's level at a time: sample() and pdf() ask for one cell each
    portal_subcell_shares(*table_, *view_, c, sub_.values());
    sub_.update();
    sub_cell_ = c;
  }
  return sub_;
}

DirectionSample PortalEnvironmentSampler::sample(Point2 u) const {
  return valid_ ? table_->sample(top_, u, this) : DirectionSample{};
}

float PortalEnvironmentSampler::pdf(Vec3 wi) const { return valid_ ? table_->pdf(top_, wi, this) : 0.0f; }

Point2 PortalEnvironmentSampler::invert(Vec3 wi) const {
  return valid_ ? table_->invert(top_, wi, this) : Point2{0.5f, 0.5f};
}

}  // namespace envpis
