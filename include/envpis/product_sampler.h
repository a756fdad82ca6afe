// SPDX-License-Identifier: Apache-2.0
// Per-shading-point product importance sampling of environment x BSDF proxy
// (Conty Estevez & Lecocq 2018, section 4).
//
// For each of the T x T top cells c of the ImportanceTable:
//     P[c] = E[c] * proxy(c)
// where proxy(c) evaluates every proxy lobe at the direction of the cell's bounding cone closest to
// that lobe's axis (vectorized over cells: AVX-512 16 lanes, AVX2 8 or SSE2 4, chosen at run time).
// A cell is chosen from the T x T CDF of P, then a direction inside it from the table's fine distribution of
// that cell, which still follows the environment only. The density of any direction w in cell c is
//     p(w) = (P[c] / sum P) * q_c(w)
// with q_c the fine density of the cell; pdf(w) returns exactly that, for MIS with BSDF sampling.
//
// Environment floor (default r = 1/8): every cell the proxy sees (P[c] > 0) keeps at least r times its
// environment share, P'[c] = max(P[c] / sum P, r E[c]), renormalized (which divides by at most 1 + r).
// So wherever the product samples at all, its density is at least r / (1 + r) of the environment
// table's: a light sample weighs at most (1 + r) / r = 9 times what the same sample weighs under mis,
// and a BSDF sample's power-heuristic contribution, at most f L / (2 p_light), likewise. A bright sun
// in a cell the proxy under-rates cannot make product a firefly that mis would not be, within that
// factor. Cells the proxy does not see (entirely below an opaque surface's horizon) stay at 0.
//
// Refinement (options.refine, on a table with sub-cells, S > 1): once a cell is chosen, one of its
// S x S sub-cells is chosen by the product again, P[s | c] = E[s | c] * proxy(s) with the proxy over
// the sub-cell's own, tighter cone and E[s | c] its environment share of the cell, floored like the
// top level (each sub-cell the proxy sees keeps at least r times its share). Then a direction inside
// the sub-cell from the table's fine distribution. The density of w in sub-cell s of cell c is
//     p(w) = (P[c] / sum P) * P[s | c] * q_s(w);
// the sub-cells' weights are computed for the chosen cell only (one vector of S^2 lanes), so the cost
// per shading point stays O(T^2), plus O(S^2) per sample() and pdf(). Without refine, the sub-cell
// comes from the environment's shares (the paper's sampler: the same density as with S = 1). With
// both floors the density wherever the product samples is at least (r / (1 + r))^2 of the
// environment table's.
//
// Cell estimate (options.cell_estimate): the cone-closest value above is an upper bound of the proxy
// over the cell, loose for every cell only partly inside a lobe, and that looseness is much of what
// separates the top level from one that knew each cell's true share (docs/refinement.md). Moments
// evaluate the lobes at the cell's importance-weighted mean direction instead (the cosine lobes from it
// and the cell's angular spread): an estimate of the importance-weighted mean of the proxy over the
// cell, at the same cost per cell. The cone still gates each side of the surface, and every lobe stays
// positive there, so the same cells are positive as with the cone.
//
// Optionally a fraction env_mix of the environment-only distribution is mixed into the top level
// (P'[c] = (1 - m) P[c] / sum P + m E[c]), a defensive mixture against cells the proxy under-rates.
//
// Fallbacks (documented, never NaN): if the proxy is all zero, or no cell has positive product
// weight, the sampler uses the environment-only distribution. If the normal or wo is zero/NaN, or
// the table is empty (all-black map), it is invalid: sample() returns pdf 0 and pdf() returns 0.
//
// Portals (issue 24; envpis/portals.h, docs/portals.md): prepare() can take a PortalView prepared for
// the shading point p (the product's other inputs, n and wo, do not locate the point; the view does).
// Each cell's weight then gains the view's visible fraction, P[c] = E[c] proxy(c) V[c], and the
// environment that the floor and env_mix refer to becomes the portal-masked one, E[c] V[c] / sum E V
// (PortalEnvironmentSampler's distribution), so every cell with V[c] = 0 keeps density 0: directions
// that provably miss every portal get no light samples, and BSDF samples carry them under MIS. The
// sub-cell level is masked likewise, E[s | c] proxy(s) V[s] when refining and E[s | c] V[s] otherwise
// (the environment's own shares in a cell where no sub-cell is estimated visible). The fallback when
// the proxy sees no visible cell is PortalEnvironmentSampler's distribution. If the view sees nothing
// (visible() false), or the proxy sees none of the visible cells (every portal behind an opaque
// surface), the sampler is invalid: no sample, pdf 0. (An all-zero proxy falls back as without portals.) Without a view (nullptr, or the
// three-argument prepare), nothing changes: the same arithmetic, bit for bit.
//
// Usage: create one ProductSampler per thread (it owns O(T^2) scratch allocated once), then per
// shading point call prepare() and any number of sample()/pdf(). Nothing allocates after construction.
// sample() and pdf() reuse the sampler's scratch too: one sampler must not be used by two threads.
#pragma once

#include <array>
#include <vector>

#include "envpis/bsdf_proxy.h"
#include "envpis/importance_table.h"
#include "envpis/portals.h"
#include "envpis/simd.h"

namespace envpis {

namespace detail {
struct Kernels;
}

/// How a cell's proxy value is estimated (the P[c] above, and P[s | c] when refining).
enum class CellEstimate {
  /// Every lobe at the direction of the cell's bounding cone closest to its axis (the paper's): an
  /// upper bound of the proxy over the cell, loose for every cell only partly inside a lobe.
  Cone,
  /// The glossy lobes at the cell's importance-weighted mean direction, the cosine lobes as their mean
  /// over the cell from that direction and the cell's angular spread (the table stores both per cell
  /// and per sub-cell): an estimate of the importance-weighted mean of the proxy over the cell, not a
  /// bound. The cone still decides which side of the surface a cell reaches.
  Moments,
};
const char* to_string(CellEstimate e);
CellEstimate parse_cell_estimate(const std::string& s);  ///< "cone" | "moments"; throws Error otherwise

struct ProductSamplerOptions {
  ProxyOptions proxy;
  float env_mix = 0.0f;  ///< fraction of the environment-only distribution mixed in, [0, 1]
  /// r: every cell the proxy sees keeps at least r times its environment share (see above), [0, 1];
  /// 0 is the paper's top level.
  float env_floor = 0.125f;
  /// Choose the sub-cell by the product too (see above); needs a table with subdivision() > 1.
  /// false: the paper's one-level product.
  bool refine = false;
  /// With refine: up to this many of the heaviest top cells (those within a factor 4 of the largest
  /// P[c]) have P[c] re-estimated from their sub-cells, E[c] * sum_s E[s | c] proxy(s), in prepare(),
  /// 0..64. It helps the light sample alone everywhere, but under MIS only rough lobes: the cells left
  /// out keep the whole cell's looser estimate and take samples from the re-estimated ones
  /// (docs/refinement.md). 0: only the chosen cell's sub-cells are weighed, when sampled.
  int refine_cells = 0;
  CellEstimate cell_estimate = CellEstimate::Cone;
  Simd simd = Simd::Best;  ///< instruction set of the weights kernel (envpis/simd.h)
};

class ProductSampler : private SubcellLevel {
 public:
  explicit ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options = {});

  /// Builds the T x T product distribution for a shading point: unit (or any non-zero) normal n,
  /// outgoing direction wo (pointing away from the surface, towards the viewer), and the proxy.
  /// Returns valid().
  bool prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy) { return prepare(n, wo, proxy, nullptr); }
  /// The same through portals (see above): `portals` prepared for the shading point, over this
  /// sampler's table, or nullptr for none. The sampler keeps the pointer until the next prepare();
  /// the view must stay prepared for the same point while sample() and pdf() are used.
  bool prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy, const PortalView* portals);

  bool valid() const { return valid_; }
  /// True when the last prepare() fell back to environment-only sampling.
  bool uses_environment_fallback() const { return fallback_; }

  /// Draws a direction for u in [0,1)^2. pdf 0 means no sample (invalid sampler).
  DirectionSample sample(Point2 u) const;
  /// Density (solid angle) of sample() at direction wi.
  float pdf(Vec3 wi) const;
  /// pdf(wi), given wi's texture coordinate in the table's map (ImportanceTable::pdf(d, texture)).
  float pdf(Vec3 wi, Point2 texture) const;
  /// pdf() at the direction of equal-area point p, given p (ImportanceTable::pdf_square).
  float pdf_square(Point2 p) const;
  /// pdf() in fine texel (x, y) of the table's equal-area grid (ImportanceTable::pdf_texel).
  float pdf_texel(int x, int y) const;
  /// The u that sample() maps to direction wi (up to round-off).
  Point2 invert(Vec3 wi) const;

  /// Whether sample() and pdf() refine inside the cell (options().refine on a table with sub-cells).
  bool refines() const { return refine_; }
  /// The current shading point's distribution over the sub-cells of cell c (the environment's shares
  /// when not refining, or when the proxy sees none of them).
  const DiscreteDistribution2D& subcells(int c) const override;

  /// Normalized top-level probability of cell c for the current shading point.
  float cell_probability(int c) const { return top_.pmf(c); }
  /// The current shading point's top level (T x T, the cells' probabilities).
  const DiscreteDistribution2D& top_level() const { return top_; }
  const PreparedProxy& prepared_proxy() const { return prepared_; }
  const ImportanceTable& table() const { return *table_; }
  const ProductSamplerOptions& options() const { return options_; }
  /// The instruction set the weights kernel runs (options().simd resolved on this CPU).
  Simd simd() const;

 private:
  const ImportanceTable* table_;
  ProductSamplerOptions options_;
  const detail::Kernels* kernels_;
  PreparedProxy prepared_;
  DiscreteDistribution2D top_;  // P[c], unnormalized (its pmf normalizes)
  float weigh_subcells(int c, DiscreteDistribution2D& out) const;
  void reestimate_heaviest_cells();
  bool apply_portals();
  bool mask_subcells(int c, const float* e, float* w, float* masked) const;
  const DiscreteDistribution2D& portal_subcells(int c) const;
  const PortalView* view_ = nullptr;  // the last prepare()'s portals, or nullptr
  std::vector<float> masked_env_;     // E[c] V[c] (padded), with a view
  float masked_scale_ = 1;            // 1 / sum E V
  mutable DiscreteDistribution2D portal_sub_;  // not refining, with a view: the last cell's E[s | c] V[s]
  mutable int portal_sub_cell_ = -1;
  // Sub-cell distributions: one per cell re-estimated in prepare(), then kRecentCells for the cells
  // sample() and pdf() needed last (a glossy lobe's light and BSDF samples spread over a dozen cells).
  static constexpr int kRecentCells = 16;
  mutable std::vector<DiscreteDistribution2D> slots_;  // refine_cells + kRecentCells
  mutable std::vector<int> slot_of_;                   // per cell: its slot, or -1
  std::vector<int> slotted_;                           // the cells re-estimated in prepare()
  mutable std::array<int, kRecentCells> recent_;  // -1: an empty slot
  mutable int next_recent_ = 0;
  bool refine_ = false;
  bool valid_ = false;
  bool fallback_ = false;
};

}  // namespace envpis
