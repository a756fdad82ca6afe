// Deterministic, counter-based random numbers: every value is a hash of (seed, pixel, sample index,
// dimension), so a pixel's samples never depend on which thread renders it or in which order tiles
// run. The same seed gives the same image at any thread count.
//
// The hash is the SplitMix64 finalizer (Steele et al. 2014; the "mix64" variant of Stafford), applied
// in a chain: key = mix(mix(mix(seed) ^ pixel) ^ sample), value = mix(key + dim * golden ratio).
#pragma once

#include <cstdint>

#include "envpis/common.h"

namespace envpis::render {

inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// Random numbers of one pixel sample. Dimensions are consumed in order by next1d()/next2d(), or
/// addressed directly with at().
class SampleRng {
 public:
  SampleRng(std::uint64_t seed, std::uint64_t pixel, std::uint64_t sample)
      : key_(mix64(mix64(mix64(seed + 0x632be59bd9b4e019ULL) ^ pixel) ^ (sample * 0x9e3779b97f4a7c15ULL))) {}

  /// Uniform float in [0, 1) of dimension `dim` (24 random bits, so never exactly 1).
  float at(std::uint32_t dim) const {
    const std::uint64_t h = mix64(key_ + (std::uint64_t(dim) + 1) * 0x9e3779b97f4a7c15ULL);
    return float(h >> 40) * 0x1p-24f;
  }
  float next1d() { return at(dim_++); }
  Point2 next2d() {
    const float a = at(dim_++);
    return {a, at(dim_++)};
  }
  std::uint32_t dimension() const { return dim_; }
  void set_dimension(std::uint32_t d) { dim_ = d; }
  /// A 64-bit hash for a further independent stream (e.g. per-shading-point jitter).
  std::uint64_t stream(std::uint32_t dim) const { return mix64(key_ ^ mix64(0xa0761d6478bd642fULL + dim)); }

 private:
  std::uint64_t key_;
  std::uint32_t dim_ = 0;
};

}  // namespace envpis::render
