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
// Optionally a fraction env_mix of the environment-only distribution is mixed into the top level
// (P'[c] = (1 - m) P[c] / sum P + m E[c]), a defensive mixture against cells the proxy under-rates.
//
// Fallbacks (documented, never NaN): if the proxy is all zero, or no cell has positive product
// weight, the sampler uses the environment-only distribution. If the normal or wo is zero/NaN, or
// the table is empty (all-black map), it is invalid: sample() returns pdf 0 and pdf() returns 0.
//
// Usage: create one ProductSampler per thread (it owns O(T^2) scratch allocated once), then per
// shading point call prepare() and any number of sample()/pdf(). prepare() does not allocate.
#pragma once

#include <vector>

#include "envpis/bsdf_proxy.h"
#include "envpis/importance_table.h"
#include "envpis/simd.h"

namespace envpis {

namespace detail {
struct Kernels;
}

struct ProductSamplerOptions {
  ProxyOptions proxy;
  float env_mix = 0.0f;  ///< fraction of the environment-only distribution mixed in, [0, 1]
  /// r: every cell the proxy sees keeps at least r times its environment share (see above), [0, 1];
  /// 0 is the paper's top level.
  float env_floor = 0.125f;
  Simd simd = Simd::Best;  ///< instruction set of the weights kernel (envpis/simd.h)
};

class ProductSampler {
 public:
  explicit ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options = {});

  /// Builds the T x T product distribution for a shading point: unit (or any non-zero) normal n,
  /// outgoing direction wo (pointing away from the surface, towards the viewer), and the proxy.
  /// Returns valid().
  bool prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy);

  bool valid() const { return valid_; }
  /// True when the last prepare() fell back to environment-only sampling.
  bool uses_environment_fallback() const { return fallback_; }

  /// Draws a direction for u in [0,1)^2. pdf 0 means no sample (invalid sampler).
  DirectionSample sample(Point2 u) const;
  /// Density (solid angle) of sample() at direction wi.
  float pdf(Vec3 wi) const;

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
  bool valid_ = false;
  bool fallback_ = false;
};

}  // namespace envpis
