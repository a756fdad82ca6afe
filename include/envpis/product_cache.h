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
//     1/255 (alpha above 1 counts as 1); its IOR, rounded in log2 to 1/64 (clamped to [1/16, 16]).
// A shading point whose key is already prepared reuses that sampler; otherwise the least recently
// used slot is prepared for the new key.
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
// Not thread-safe: one cache per thread, like ProductSampler. Nothing allocates after construction.
#pragma once

#include <cstdint>
#include <vector>

#include "envpis/product_sampler.h"

namespace envpis {

struct ProductCacheOptions {
  int resolution = 64;   ///< K: normal and wo components rounded to multiples of 1/K, 1..4095
  int entries = 16;      ///< samplers kept (each O(T^2) memory), 1..1024
};

class ProductCache {
 public:
  /// Throws Error for options out of range (and whatever ProductSampler throws).
  ProductCache(const ImportanceTable& table, const ProductSamplerOptions& sampler = {},
               const ProductCacheOptions& options = {});

  /// The sampler prepared for the key of (n, wo, proxy) (see above). The reference stays valid until
  /// the next prepare(). A zero or NaN n or wo gives an invalid sampler, as ProductSampler::prepare.
  const ProductSampler& prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy);

  /// The rounded shading point prepare() prepares for: what key() rounds n, wo and proxy to.
  struct Rounded {
    Vec3 n, wo;
    BsdfProxy proxy;
  };
  Rounded round(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const;

  std::uint64_t hits() const { return hits_; }
  std::uint64_t misses() const { return misses_; }
  const ProductCacheOptions& options() const { return options_; }

 private:
  struct Key {
    std::uint64_t n = 0, wo = 0, proxy = 0;
    bool operator==(const Key& o) const { return n == o.n && wo == o.wo && proxy == o.proxy; }
  };
  Key key(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const;
  Rounded rounded(const Key& k) const;  // the point a key stands for

  ProductCacheOptions options_;
  std::vector<ProductSampler> samplers_;
  std::vector<Key> keys_;
  std::vector<std::uint64_t> last_use_;  // 0: the slot holds no key yet
  ProductSampler invalid_;               // never prepared with a valid point: for zero or NaN n, wo
  std::size_t last_ = 0;                 // the slot prepare() returned last
  std::uint64_t clock_ = 0, hits_ = 0, misses_ = 0;
};

}  // namespace envpis
