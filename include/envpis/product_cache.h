// SPDX-License-Identifier: Apache-2.0
// Product distributions shared by shading points that round to the same key.
//
// ProductSampler::prepare weighs every top cell at each shading point. At a renderer's first hit that
// work repeats for every sample of a pixel, although the samples' shading points barely differ. A
// ProductCache prepares each of its samplers for a rounded shading point, its key:
//   - the normal and wo: each component of the unit vector rounded to a multiple of 1/K (K the
//     resolution), then normalized; the direction moves by at most sqrt(3) / (2 K) radians (0.78
//     degree at the default K = 64). No trigonometry: the key costs a few multiplications;
//   - the proxy's four lobe weights as fractions of their sum, rounded to 1/255 (a positive weight
//     keeps at least 1/255, so no lobe disappears); its two roughnesses, rounded in sqrt(alpha) to
//     1/255 (alpha above 1 counts as 1); its IOR, rounded in log2 to 1/64 (clamped to [1/16, 16]);
//   - a proxy with neither reflection nor refraction (diffuse, translucent) is the same for every wo
//     on one side of the surface, so its key holds n or -n, whichever is on wo's side, in place of wo:
//     the hits of a flat diffuse surface share one key whatever the view.
// A shading point whose key is already prepared reuses that sampler; otherwise a slot not used
// since the eviction hand last passed it (CLOCK, an approximation of least recently used) is prepared
// for the new key. Keys are found through a hash index, so a large cache costs no more per point
// than a small one.
//
// The distribution used at a shading point is therefore a function of the point alone (through its
// key), never of the points before it or of the cache's size: a reused sampler is identical to one
// prepared afresh. A renderer that draws the light sample and evaluates the BSDF sample's MIS weight
// with the sampler it gets here uses one exact density for both, and its image does not depend on the
// order of the samples or on the threads. The density differs from the unrounded point's product only
// by the rounding. Where the rounded
// normal's horizon hides a cell the true one sees, the light sample has no density there and the BSDF
// sample carries that part alone, as MIS does with any light distribution.
//
// With portals (the second constructor) the distribution also depends on the shading point p, through
// a PortalView (envpis/portals.h). The key then gains p, each coordinate rounded to a multiple of
// position_step, and every slot owns a view prepared at its key's rounded point, so the samples of a
// pixel share one view and one prepared product. The rounded point moves by at most sqrt(3) / 2
// position_step, which shifts a portal's spherical polygon by at most that over the portal's distance:
// a step of 1/K of a portal's size moves it by under 1/K of the portal's own angular size, from any
// distance. Where the rounded point sees a cell the true one cannot, a light sample there meets a wall
// (visibility is traced; the density stays the one pdf() returns); where it masks a cell the true one
// sees through a portal, BSDF samples carry that part alone. When the key's distribution is invalid
// (its point sees no portal: p rounded across a window's plane, or the rounded normal hides every
// portal) or p is out of the key's range, prepare() prepares exactly at the shading point instead:
// still a function of the shading point alone.
//
// Not thread-safe: one cache per thread, like ProductSampler. Nothing allocates after construction.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "envpis/portals.h"
#include "envpis/product_sampler.h"

namespace envpis {

struct ProductCacheOptions {
  int resolution = 64;   ///< K: normal and wo components rounded to multiples of 1/K, 1..4095
  int entries = 64;      ///< samplers kept (each O(T^2) memory), 1..1024
  /// With portals: the shading point's coordinates are rounded to multiples of this (world units),
  /// finite and > 0. Points beyond 2^20 steps from the origin are prepared exactly.
  float position_step = 0.05f;
};

class ProductCache {
 public:
  /// Throws Error for options out of range (and whatever ProductSampler throws).
  ProductCache(const ImportanceTable& table, const ProductSamplerOptions& sampler = {},
               const ProductCacheOptions& options = {});
  /// Through portals: every slot gets a PortalView of `portals` (copied) with `view` options; use the
  /// four-argument prepare(). Throws Error for an empty set of portals or a bad position_step.
  ProductCache(const ImportanceTable& table, const Portals& portals, const ProductSamplerOptions& sampler = {},
               const ProductCacheOptions& options = {}, const PortalViewOptions& view = {});

  /// The sampler prepared for the key of (n, wo, proxy) (see above). The reference stays valid until
  /// the next prepare(). A zero or NaN n or wo gives an invalid sampler, as ProductSampler::prepare.
  /// Without portals only (throws Error on a cache with portals).
  const ProductSampler& prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy);
  /// With portals only: the sampler prepared through the portals for the key of (p, n, wo, proxy), or,
  /// when that one is invalid or p has no key, for the shading point exactly (see above). The
  /// reference stays valid until the next prepare(); invalid when neither sees a portal.
  const ProductSampler& prepare(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy);

  /// The rounded shading point prepare() prepares for: what key() rounds n, wo and proxy to (and p,
  /// with portals; p itself when it has no key).
  struct Rounded {
    Vec3 n, wo;
    BsdfProxy proxy;
    Vec3 p;
  };
  Rounded round(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const;
  Rounded round(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy) const;
  bool has_portals() const { return !views_.empty(); }

  std::uint64_t hits() const { return hits_; }
  std::uint64_t misses() const { return misses_; }
  /// With portals: shading points prepared exactly (no key, or the key's distribution invalid).
  std::uint64_t exact_points() const { return exact_points_; }
  const ProductCacheOptions& options() const { return options_; }

 private:
  struct Key {
    std::uint64_t n = 0, wo = 0, proxy = 0, p = 0;  // p: 0 without portals
    bool operator==(const Key& o) const { return n == o.n && wo == o.wo && proxy == o.proxy && p == o.p; }
  };
  Key key(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const;
  Rounded rounded(const Key& k) const;  // the point a key stands for
  std::size_t slot_for(const Key& k, bool& prepared);  // the slot holding k, or the one to prepare for it
  const ProductSampler& exactly(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy);

  ProductCacheOptions options_;
  std::vector<ProductSampler> samplers_;
  std::vector<PortalView> views_;  // with portals: one per slot, then the exact point's last
  std::vector<Key> keys_;
  std::vector<char> used_;        // the slot holds a key
  std::vector<char> referenced_;  // used since the eviction hand last passed it
  std::vector<std::int32_t> index_;  // open addressing, linear probing: slot + 1, or 0 for empty
  int index_shift_ = 62;             // 64 - log2(index_.size())
  std::size_t hand_ = 0;             // the eviction hand (CLOCK)
  std::size_t home(const Key& k) const;        // k's first position in index_
  std::size_t find_index(const Key& k) const;  // k's position in index_, or the empty one that ends its probe
  void erase_index(std::size_t pos);           // removes index_[pos], shifting its probe chain back
  std::vector<char> valid_;              // with portals: the slot's sampler is valid
  std::unique_ptr<ProductSampler> exact_;  // with portals: prepared at the shading point itself
  ProductSampler invalid_;               // never prepared with a valid point: for zero or NaN n, wo
  std::size_t last_ = 0;                 // the slot prepare() returned last
  std::uint64_t hits_ = 0, misses_ = 0, exact_points_ = 0;
};

}  // namespace envpis
