// SPDX-License-Identifier: Apache-2.0
#include "envpis/product_cache.h"

#include <algorithm>
#include <cmath>
#include <string>


namespace envpis {
namespace {

constexpr float kSteps = 255.0f;  // of a weight fraction and of sqrt(alpha)
constexpr float kIorStepsPerOctave = 64.0f;
constexpr float kIorOctaves = 4.0f;  // IOR clamped to [2^-4, 2^4]

// A direction's lattice point: each component of the unit direction rounded to a multiple of 1/K,
// packed as three 13-bit fields (|component| <= K < 4096). Inline: the key's two run in parallel.
inline __attribute__((always_inline)) std::uint64_t lattice_point(Vec3 d, int k) {
  const float K = float(k);
  const float scale = K / std::sqrt(dot(d, d));  // one division for the three components
  // c K + K + 1/2 >= 0, so the conversion's truncation rounds to nearest (lround is a library call);
  // through int32, which converts in one instruction (uint64 does not without AVX-512).
  auto field = [&](float c) {
    return std::uint64_t(static_cast<std::uint32_t>(static_cast<std::int32_t>(c * scale + K + 0.5f)) & 0x1fffu);
  };
  return field(d.x) | field(d.y) << 13 | field(d.z) << 26;
}
Vec3 lattice_direction(std::uint64_t p, int k) {
  auto component = [&](int shift) { return float(static_cast<long>((p >> shift) & 0x1fff) - k); };
  return normalize(Vec3{component(0), component(13), component(26)});
}

// A position's lattice point: each coordinate over the step rounded to nearest, offset by 2^20 into
// three 21-bit fields; bit 63 set, so that 0 stays "no position" (a cache without portals). False when
// a coordinate is 2^20 steps or more from the origin, or not finite.
constexpr float kPositionRange = float(1 << 20) - 1.0f;
bool position_point(Vec3 p, float step, std::uint64_t& out) {
  const float c[3] = {p.x / step, p.y / step, p.z / step};
  std::uint64_t k = std::uint64_t(1) << 63;
  for (int i = 0; i < 3; ++i) {
    if (!(std::fabs(c[i]) < kPositionRange)) return false;
    const auto q = static_cast<std::int64_t>(std::floor(c[i] + 0.5f)) + (std::int64_t(1) << 20);
    k |= static_cast<std::uint64_t>(q) << (21 * i);
  }
  out = k;
  return true;
}
Vec3 position_of(std::uint64_t k, float step) {
  auto c = [&](int i) { return float(static_cast<std::int64_t>((k >> (21 * i)) & 0x1fffff) - (std::int64_t(1) << 20)) * step; };
  return {c(0), c(1), c(2)};
}

float finite_weight(float w) { return std::isfinite(w) && w > 0 ? w : 0.0f; }

// A lobe weight as a fraction of the sum in 1/255 steps; a positive weight keeps at least one step.
std::uint32_t weight_steps(float w, float sum) {
  if (!(w > 0)) return 0;
  return std::clamp(static_cast<std::uint32_t>(w / sum * kSteps + 0.5f), 1u, static_cast<std::uint32_t>(kSteps));
}

std::uint32_t alpha_steps(float alpha) {
  const float a = std::isfinite(alpha) ? std::clamp(alpha, 0.0f, 1.0f) : 1.0f;
  return static_cast<std::uint32_t>(std::sqrt(a) * kSteps + 0.5f);
}
float alpha_of(std::uint32_t steps) {
  const float s = float(steps) / kSteps;
  return s * s;
}

// IOR 1 (every key without a refraction lobe) skips log2 and exp2: the same steps and value, for less.
constexpr std::uint32_t kIorOneSteps = static_cast<std::uint32_t>(kIorOctaves * kIorStepsPerOctave);
std::uint32_t ior_steps(float ior) {
  if (ior == 1.0f) return kIorOneSteps;
  const float e = std::isfinite(ior) && ior > 0 ? std::log2(ior) : 0.0f;
  const float c = std::clamp(e, -kIorOctaves, kIorOctaves);
  return static_cast<std::uint32_t>((c + kIorOctaves) * kIorStepsPerOctave + 0.5f);
}
float ior_of(std::uint32_t steps) {
  return steps == kIorOneSteps ? 1.0f : std::exp2(float(steps) / kIorStepsPerOctave - kIorOctaves);
}

}  // namespace

ProductCache::ProductCache(const ImportanceTable& table, const ProductSamplerOptions& sampler,
                           const ProductCacheOptions& options)
    : options_(options), invalid_(table, sampler) {
  if (options.resolution < 1 || options.resolution > 4095)
    throw Error("product cache: resolution must be in 1..4095, got " + std::to_string(options.resolution));
  if (options.entries < 1 || options.entries > 1024)
    throw Error("product cache: entries must be in 1..1024, got " + std::to_string(options.entries));
  samplers_.reserve(static_cast<std::size_t>(options.entries));
  for (int i = 0; i < options.entries; ++i) samplers_.emplace_back(table, sampler);
  keys_.assign(samplers_.size(), Key{});
  used_.assign(samplers_.size(), 0);
  referenced_.assign(samplers_.size(), 0);
  int bits = 2;
  while ((std::size_t(1) << bits) < 2 * samplers_.size()) ++bits;  // at most half full: short probe chains
  index_.assign(std::size_t(1) << bits, 0);
  index_shift_ = 64 - bits;
}

ProductCache::ProductCache(const ImportanceTable& table, const Portals& portals, const ProductSamplerOptions& sampler,
                           const ProductCacheOptions& options, const PortalViewOptions& view)
    : ProductCache(table, sampler, options) {
  if (portals.empty()) throw Error("product cache: no portals (use the constructor without portals)");
  if (!(std::isfinite(options.position_step) && options.position_step > 0))
    throw Error("product cache: position_step must be finite and > 0, got " + std::to_string(options.position_step));
  views_.reserve(samplers_.size() + 1);  // never reallocated: the samplers keep pointers to their views
  for (std::size_t i = 0; i <= samplers_.size(); ++i) views_.emplace_back(table, portals, view);
  valid_.assign(samplers_.size(), 0);
  exact_ = std::make_unique<ProductSampler>(table, sampler);
}

ProductCache::Key ProductCache::key(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const {
  Key k;
  k.n = lattice_point(n, options_.resolution);

  const float w[4] = {finite_weight(proxy.diffuse), finite_weight(proxy.translucent), finite_weight(proxy.reflection),
                      finite_weight(proxy.refraction)};
  const float sum = w[0] + w[1] + w[2] + w[3];
  std::uint32_t q[4] = {};
  for (int i = 0; i < 4; ++i) q[i] = sum > 0 && std::isfinite(sum) ? weight_steps(w[i], sum) : 0;
  // A lobe's roughness (and the refraction's IOR) only count when the lobe does: one key for the rest.
  // Without a glossy lobe the proxy depends on wo only through its side of the surface (which way the
  // cosine lobes face): the key takes the normal on that side for wo, so a flat diffuse floor's hits
  // share one key whatever the view.
  const bool glossy = q[2] || q[3];
  k.wo = lattice_point(glossy ? wo : dot(n, wo) < 0 ? -n : n, options_.resolution);
  const std::uint32_t ar = q[2] ? alpha_steps(proxy.alpha_reflection) : 0;
  const std::uint32_t at = q[3] ? alpha_steps(proxy.alpha_refraction) : 0;
  const std::uint32_t ior = q[3] ? ior_steps(proxy.ior) : ior_steps(1.0f);
  k.proxy = std::uint64_t(q[0]) | std::uint64_t(q[1]) << 8 | std::uint64_t(q[2]) << 16 | std::uint64_t(q[3]) << 24 |
            std::uint64_t(ar) << 32 | std::uint64_t(at) << 40 | std::uint64_t(ior) << 48;
  return k;
}

ProductCache::Rounded ProductCache::rounded(const Key& k) const {
  auto field = [&](int shift) { return static_cast<std::uint32_t>((k.proxy >> shift) & 0xff); };
  Rounded r;
  r.n = lattice_direction(k.n, options_.resolution);
  r.wo = lattice_direction(k.wo, options_.resolution);
  BsdfProxy& p = r.proxy;
  p.diffuse = float(field(0)) / kSteps;
  p.translucent = float(field(8)) / kSteps;
  p.reflection = float(field(16)) / kSteps;
  p.refraction = float(field(24)) / kSteps;
  p.alpha_reflection = alpha_of(field(32));
  p.alpha_refraction = alpha_of(field(40));
  p.ior = ior_of(static_cast<std::uint32_t>(k.proxy >> 48));
  r.p = k.p ? position_of(k.p, options_.position_step) : Vec3{0, 0, 0};
  return r;
}

ProductCache::Rounded ProductCache::round(Vec3 n, Vec3 wo, const BsdfProxy& proxy) const {
  if (!is_valid_direction(n) || !is_valid_direction(wo)) return {};
  return rounded(key(n, wo, proxy));
}

ProductCache::Rounded ProductCache::round(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy) const {
  if (!is_valid_direction(n) || !is_valid_direction(wo)) return {};
  Key k = key(n, wo, proxy);
  Rounded r = rounded(k);
  r.p = position_point(p, options_.position_step, k.p) ? position_of(k.p, options_.position_step) : p;
  return r;
}

const ProductSampler& ProductCache::prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  if (has_portals()) throw Error("product cache: a cache with portals needs the shading point (prepare(p, n, wo, proxy))");
  if (!is_valid_direction(n) || !is_valid_direction(wo)) {
    invalid_.prepare(n, wo, proxy);  // only invalidates
    return invalid_;
  }
  bool prepared = false;
  const std::size_t i = slot_for(key(n, wo, proxy), prepared);
  if (!prepared) {
    const Rounded r = rounded(keys_[i]);  // from the key alone, so a point's distribution is its key's
    samplers_[i].prepare(r.n, r.wo, r.proxy);
  }
  return samplers_[i];
}

const ProductSampler& ProductCache::prepare(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  if (!has_portals()) throw Error("product cache: prepare(p, n, wo, proxy) needs a cache with portals");
  if (!is_valid_direction(n) || !is_valid_direction(wo)) {
    invalid_.prepare(n, wo, proxy);  // only invalidates
    return invalid_;
  }
  Key k = key(n, wo, proxy);
  if (!position_point(p, options_.position_step, k.p)) return exactly(p, n, wo, proxy);
  bool prepared = false;
  const std::size_t i = slot_for(k, prepared);
  if (!prepared) {
    const Rounded r = rounded(k);
    PortalView& view = views_[i];
    valid_[i] = view.prepare(r.p) && samplers_[i].prepare(r.n, r.wo, r.proxy, &view);
  }
  return valid_[i] ? samplers_[i] : exactly(p, n, wo, proxy);
}

const ProductSampler& ProductCache::exactly(Vec3 p, Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  ++exact_points_;
  PortalView& view = views_.back();
  view.prepare(p);  // when it sees nothing, the sampler's prepare leaves it invalid
  exact_->prepare(n, wo, proxy, &view);
  return *exact_;
}

// Multiplicative hashing: each field by its own odd constant, folded, and the product's top bits (the
// best mixed) as the position.
std::size_t ProductCache::home(const Key& k) const {
  std::uint64_t h = k.n * 0x9e3779b97f4a7c15ull ^ k.wo * 0xc2b2ae3d27d4eb4full ^ k.proxy * 0x165667b19e3779f9ull ^
                    k.p * 0xd6e8feb86659fd93ull;
  h ^= h >> 29;
  return static_cast<std::size_t>((h * 0xff51afd7ed558ccdull) >> index_shift_);
}

std::size_t ProductCache::find_index(const Key& k) const {
  const std::size_t mask = index_.size() - 1;
  std::size_t pos = home(k);
  while (index_[pos] != 0 && !(keys_[static_cast<std::size_t>(index_[pos] - 1)] == k)) pos = (pos + 1) & mask;
  return pos;
}

void ProductCache::erase_index(std::size_t pos) {
  // Backward-shift deletion: later entries of the chain move into the hole when their home position
  // does not lie cyclically in (hole, their position], so every probe still reaches them.
  const std::size_t mask = index_.size() - 1;
  std::size_t hole = pos;
  for (std::size_t i = (pos + 1) & mask; index_[i] != 0; i = (i + 1) & mask) {
    const std::size_t h = home(keys_[static_cast<std::size_t>(index_[i] - 1)]);
    const bool stays = hole <= i ? (hole < h && h <= i) : (hole < h || h <= i);
    if (stays) continue;
    index_[hole] = index_[i];
    hole = i;
  }
  index_[hole] = 0;
}

std::size_t ProductCache::slot_for(const Key& k, bool& prepared) {
  prepared = true;
  if (used_[last_] && keys_[last_] == k) {  // consecutive samples of a pixel: the usual hit
    ++hits_;
    referenced_[last_] = 1;
    return last_;
  }
  const std::size_t pos = find_index(k);
  if (index_[pos] != 0) {
    ++hits_;
    last_ = static_cast<std::size_t>(index_[pos] - 1);
    referenced_[last_] = 1;
    return last_;
  }
  // A miss: the hand passes referenced slots (clearing their mark) up to one that is not.
  while (referenced_[hand_]) {
    referenced_[hand_] = 0;
    hand_ = (hand_ + 1) % keys_.size();
  }
  const std::size_t victim = hand_;
  hand_ = (hand_ + 1) % keys_.size();
  if (used_[victim]) erase_index(find_index(keys_[victim]));
  ++misses_;
  keys_[victim] = k;
  used_[victim] = 1;
  referenced_[victim] = 1;
  index_[find_index(k)] = static_cast<std::int32_t>(victim + 1);
  prepared = false;
  last_ = victim;
  return victim;
}

}  // namespace envpis
