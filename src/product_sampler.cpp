// SPDX-License-Identifier: Apache-2.0
#include "envpis/product_sampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "envpis/equal_area.h"
#include "envpis/portal_sampler.h"
#include "kernels.h"
#include "proxy_internal.h"

namespace envpis {

const char* to_string(CellEstimate e) { return e == CellEstimate::Moments ? "moments" : "cone"; }

CellEstimate parse_cell_estimate(const std::string& s) {
  if (s == "cone") return CellEstimate::Cone;
  if (s == "moments") return CellEstimate::Moments;
  throw Error("unknown cell estimate '" + s + "' (cone, moments)");
}

namespace {
detail::LobeParams lobe_params(const PreparedProxy& proxy, CellEstimate estimate) {
  detail::LobeParams l = detail::to_lobe_params(proxy);
  l.moments = estimate == CellEstimate::Moments;
  return l;
}
}  // namespace

ProductSampler::ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options)
    : table_(&table),
      options_(options),
      top_(table.top_resolution(), table.top_resolution()),
      portal_sub_(table.subdivision(), table.subdivision()) {
  if (!(options.env_mix >= 0.0f && options.env_mix <= 1.0f)) throw Error("env_mix must be in [0, 1]");
  if (!(options.env_floor >= 0.0f && options.env_floor <= 1.0f)) throw Error("env_floor must be in [0, 1]");
  if (options.refine_cells < 0 || options.refine_cells > 64) throw Error("refine_cells must be in 0..64");
  kernels_ = &detail::kernels_for(options.simd);
  if (options.refine && table.subdivision() < 2)
    throw Error("the refined product sampler needs a table with sub-cells (subdivision > 1)");
  refine_ = options.refine;
  recent_.fill(-1);
  if (refine_) {
    slots_.assign(static_cast<std::size_t>(options.refine_cells) + kRecentCells,
                  DiscreteDistribution2D(table.subdivision(), table.subdivision()));
    slot_of_.assign(static_cast<std::size_t>(table.cell_count()), -1);
    slotted_.reserve(static_cast<std::size_t>(options.refine_cells));
  }
}

Simd ProductSampler::simd() const { return parse_simd(kernels_->name); }

// With a view: the portal-masked environment E[c] V[c] into masked_env_, unnormalized, and
// 1 / sum E V into masked_scale_; false when it is all zero (the view sees only black cells).
bool ProductSampler::apply_portals() {
  const int cells = table_->cell_count();
  masked_env_.resize(static_cast<std::size_t>(top_.padded_size()));
  const float* e = table_->top_level().values();
  const float* v = view_->cell_fractions();
  float part[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // eight running sums: no chain of dependent adds
  int c = 0;
  for (; c + 8 <= cells; c += 8)
    for (int k = 0; k < 8; ++k) part[k] += masked_env_[c + k] = e[c + k] * v[c + k];
  for (; c < cells; ++c) part[0] += masked_env_[c] = e[c] * v[c];
  const float sum = ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7]));
  if (!(sum >= std::numeric_limits<float>::min()) || !std::isfinite(sum)) return false;
  masked_scale_ = 1.0f / sum;
  return true;
}

bool ProductSampler::prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy, const PortalView* portals) {
  valid_ = false;
  fallback_ = false;
  view_ = portals;
  portal_sub_cell_ = -1;
  for (int c : slotted_) slot_of_[c] = -1;
  slotted_.clear();
  for (int& c : recent_) {
    if (c >= 0) slot_of_[c] = -1;
    c = -1;
  }
  if (table_->empty() || !is_valid_direction(n) || !is_valid_direction(wo)) return false;
  if (view_ && (&view_->table() != table_ || !view_->visible() || !apply_portals())) return false;
  const int cells = table_->cell_count();
  prepared_ = prepare_proxy(proxy, n, wo, options_.proxy);
  float m = options_.env_mix;
  float* prob = top_.values();
  float sum = 0;
  bool seen = false;
  if (prepared_.valid()) {
    sum = kernels_->product_weights(detail::cell_arrays(*table_), lobe_params(prepared_, options_.cell_estimate), prob);
    if (view_) {  // the portal factor (a re-estimated cell gets it from its sub-cells instead)
      const float* v = view_->cell_fractions();
      for (int c = 0; c < cells; ++c) prob[c] *= v[c];
    }
    if (refine_) reestimate_heaviest_cells();
    // The kernel's total holds unless a pass above changed the weights; the row sums only once, after
    // the last pass below (update()).
    if (view_ || !slotted_.empty()) sum = top_.sum();
    seen = DiscreteDistribution2D::valid_total(sum);
  }
  // Nothing the proxy can see: environment only. A total below FLT_MIN (denormal lobe weights) counts
  // as nothing too: its reciprocal would overflow to inf and so would every pdf (found by fuzzing).
  // Through portals, a proxy that sees none of the visible cells (every portal behind an opaque
  // surface) leaves nothing to sample: invalid. Only an all-zero proxy falls back, as without portals.
  if (!seen && view_ && prepared_.valid()) {
    top_.update();  // an invalid top level, as top_level() then reports
    return false;
  }
  if (!seen) {
    fallback_ = true;
    m = 1.0f;
  }
  // E[c], or through portals the masked environment: the floor and the mixture then keep V[c] = 0 at 0.
  // (Unnormalized: every use scales it by es, which is exactly 1 without a view, so that r * es is r.)
  const float* e = view_ ? masked_env_.data() : table_->top_level().values();
  const float es = view_ ? masked_scale_ : 1.0f;
  if (!fallback_ && options_.env_floor > 0.0f) {  // the environment floor (see product_sampler.h)
    // In this instruction set's lanes, a select and not a branch: through portals the positive cells
    // are few and scattered (a branch mispredicts). The same values as `if (prob > 0) prob = max(...)`.
    kernels_->floor_weights(prob, e, cells, 1.0f / sum, options_.env_floor * es);
    if (m > 0.0f) sum = top_.sum();  // only the mixture needs the floored total
  }
  if (m > 0.0f) {  // defensive mixture with the environment distribution
    const float a = m < 1.0f ? (1.0f - m) / sum : 0.0f;
    m *= es;
    for (int c = 0; c < cells; ++c) {
      // Not a * prob[c] when a == 0: the fallback after an infinite product weight would give 0 * inf = NaN.
      prob[c] = (a > 0.0f ? a * prob[c] : 0.0f) + m * e[c];
    }
  }
  // The masses stay unnormalized: the distribution scales u by the total and its pmf by the inverse.
  top_.update();
  valid_ = top_.valid();
  return valid_;
}

// P[s | c] for cell c into `out`: E[s | c] proxy(s) over the sub-cells' cones, floored like the top
// level. Returns sum_s E[s | c] proxy(s) before the floor; 0 when the proxy sees none of the
// sub-cells, and `out` then holds the environment's shares.
float ProductSampler::weigh_subcells(int c, DiscreteDistribution2D& out) const {
  const detail::CellArrays cells = detail::subcell_arrays(*table_, c);
  float sum = kernels_->product_weights(cells, lobe_params(prepared_, options_.cell_estimate), out.values());
  const int n = table_->subdivision() * table_->subdivision();
  float* w = out.values();
  const float* env = cells.prob;  // E[s | c], or through portals the masked shares
  float masked[64];
  if (view_ && mask_subcells(c, cells.prob, w, masked)) {
    env = masked;
    sum = out.sum();  // the masked weights' total (the kernel's is unmasked); the row sums after the floor
  }
  if (!DiscreteDistribution2D::valid_total(sum)) {
    std::copy(env, env + n, w);
    out.update();
    return 0.0f;
  }
  if (options_.env_floor > 0.0f) kernels_->floor_weights(w, env, n, 1.0f / sum, options_.env_floor);
  out.update();
  return sum;
}

// Through portals: multiplies the proxy weights w of cell c's sub-cells by their fractions V[s] and
// writes the masked environment shares E[s | c] V[s] / sum (S^2 <= 64) into `masked`. False (w and
// masked untouched) when no sub-cell is estimated visible: the cell then keeps its unmasked level.
bool ProductSampler::mask_subcells(int c, const float* e, float* w, float* masked) const {
  const int n = table_->subdivision() * table_->subdivision();
  float v[64], sum = 0;
  if (!view_->subcell_fractions(c, v)) return false;
  for (int s = 0; s < n; ++s) sum += masked[s] = e[s] * v[s];
  if (!(sum > 0.0f)) return false;
  for (int s = 0; s < n; ++s) {
    masked[s] /= sum;
    w[s] *= v[s];
  }
  return true;
}

// Not refining, through portals: cell c's sub-cell level E[s | c] V[s] (PortalEnvironmentSampler's).
const DiscreteDistribution2D& ProductSampler::portal_subcells(int c) const {
  if (c != portal_sub_cell_) {
    portal_subcell_shares(*table_, *view_, c, portal_sub_.values());
    portal_sub_.update();
    portal_sub_cell_ = c;
  }
  return portal_sub_;
}

// The heaviest cells' P[c] from their sub-cells (ProductSamplerOptions::refine_cells), keeping their
// sub-cell distributions for sample() and pdf().
void ProductSampler::reestimate_heaviest_cells() {
  const int cells = table_->cell_count(), k_max = options_.refine_cells;
  if (k_max == 0) return;
  float* prob = top_.values();
  float peak = 0;
  for (int c = 0; c < cells; ++c) peak = std::max(peak, prob[c]);
  const float threshold = 0.25f * peak;
  if (!(peak > 0) || !std::isfinite(peak)) return;
  const float* e = table_->top_level().values();
  for (int c = 0; c < cells && static_cast<int>(slotted_.size()) < k_max; ++c) {
    if (!(prob[c] >= threshold)) continue;
    const int slot = static_cast<int>(slotted_.size());
    slot_of_[c] = slot;
    slotted_.push_back(c);
    prob[c] = e[c] * weigh_subcells(c, slots_[slot]);
  }
}

const DiscreteDistribution2D& ProductSampler::subcells(int c) const {
  if (!refine_ || fallback_ || !valid_) return view_ && valid_ ? portal_subcells(c) : table_->subcells(c);
  if (slot_of_[c] >= 0) return slots_[slot_of_[c]];
  // The least recently weighed of the last slots: a cell's weights are a function of the shading
  // point, so keeping them only saves time (a reused shading point samples the same few cells).
  const int i = next_recent_;
  next_recent_ = (i + 1) % kRecentCells;
  if (recent_[i] >= 0) slot_of_[recent_[i]] = -1;
  recent_[i] = c;
  const int slot = options_.refine_cells + i;
  slot_of_[c] = slot;
  weigh_subcells(c, slots_[slot]);
  return slots_[slot];
}

DirectionSample ProductSampler::sample(Point2 u) const {
  return valid_ ? table_->sample(top_, u, this) : DirectionSample{};
}

float ProductSampler::pdf(Vec3 wi) const { return valid_ ? table_->pdf(top_, wi, this) : 0.0f; }

float ProductSampler::pdf(Vec3 wi, Point2 texture) const { return valid_ ? table_->pdf(top_, wi, texture, this) : 0.0f; }

float ProductSampler::pdf_square(Point2 p) const { return valid_ ? table_->pdf_square(top_, p, this) : 0.0f; }

float ProductSampler::pdf_texel(int x, int y) const { return valid_ ? table_->pdf_texel(top_, x, y, this) : 0.0f; }

Point2 ProductSampler::invert(Vec3 wi) const { return valid_ ? table_->invert(top_, wi, this) : Point2{0.5f, 0.5f}; }

}  // namespace envpis
