// SPDX-License-Identifier: Apache-2.0
// The random numbers of one pixel sample: independent uniform numbers, or Owen-scrambled Sobol points
// (render/sobol.h), the default.
//
// Dimensions are consumed in order by next1d() / next2d(); set_dimension() jumps to a fixed block
// (the integrator gives each path vertex its own, so a vertex's numbers do not depend on what earlier
// vertices consumed). Every value is a function of (kind, seed, pixel, sample index, dimension) only,
// so a pixel's samples never depend on which thread renders it or in which order tiles run.
//
// Sobol: dimension d < 64 of a pixel's sample i is dimension d of point shuffle(i) of the Sobol
// sequence (Joe-Kuo direction numbers), Owen-scrambled per (pixel, dimension). The shuffle, one per
// pixel, maps every aligned block of 2^m indices onto an aligned block, so the first 2^m samples of a
// pixel are a (t,m,s)-net in all these dimensions at once: the pixel position, the light sample and
// the BSDF sample are stratified jointly, not only pair by pair. Dimensions from 64 on (deep path
// vertices) are padded pairs: 2D (0,2)-sequences with their own scramble and shuffle.
//
// Padded: only the pixel position comes from the full sequence; every later pair is a padded pair.
// Each pair is then better stratified on its own, but no longer jointly with the pixel position
// (docs/sampling.md measures where each wins).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "envpis/common.h"
#include "render/hash.h"
#include "render/sobol.h"

namespace envpis::render {

enum class SamplerKind { Independent, Sobol, Padded };
/// "independent" | "sobol" | "padded"; throws Error otherwise.
SamplerKind parse_sampler(const std::string& s);
const char* to_string(SamplerKind k);

/// What the samples of one pixel share, computed once per pixel: the pixel's key, the index
/// shuffle's seed and the scramble seeds of the first dimensions (the pixel position and the first
/// vertices' numbers).
class PixelSeeds {
 public:
  PixelSeeds(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel)
      : kind_(kind),
        pixel_key_(mix64(mix64(seed + 0x632be59bd9b4e019ULL) ^ pixel)),
        key_(mix64(pixel_key_)),
        shuffle_seed_(static_cast<std::uint32_t>(mix64(key_ ^ 0x2545f4914f6cdd1dULL))),
        tables_(sobol::nibble_tables(0)) {
    for (std::uint32_t d = 0; d < kCached; ++d) x_[d] = scramble(key_, d).x;
  }
  SamplerKind kind() const { return kind_; }

  /// The per-(seed, pixel, dimension) hash from which a dimension's scrambles derive.
  static std::uint64_t scramble_key(std::uint64_t key, std::uint32_t dim) {
    return mix64(key + (std::uint64_t(dim) + 1) * 0x9e3779b97f4a7c15ULL);
  }
  /// The per-(seed, pixel, dimension) scrambles: the same for all samples of the pixel, as the
  /// sequence's stratification needs.
  static sobol::Scramble scramble(std::uint64_t key, std::uint32_t dim) {
    const std::uint64_t a = scramble_key(key, dim);
    const std::uint64_t b = mix64(a ^ 0x5851f42d4c957f2dULL);
    return {static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(a >> 32), static_cast<std::uint32_t>(b)};
  }

 private:
  friend class PixelSampler;
  static constexpr std::uint32_t kCached = 16;  // dimensions of the pixel and the first two vertices
  SamplerKind kind_;
  std::uint64_t pixel_key_;  // the pixel's hash (independent numbers add the sample index to it)
  std::uint64_t key_;        // the Sobol samplers' key (the same for all samples of the pixel)
  std::uint32_t shuffle_seed_;
  const std::uint32_t* tables_;
  std::array<std::uint32_t, kCached> x_;  // scramble(key_, d).x of the full sequence's first dimensions
};

class PixelSampler {
 public:
  PixelSampler(const PixelSeeds& pixel, std::uint64_t sample)
      : kind_(pixel.kind_),
        index_(static_cast<std::uint32_t>(sample)),
        key_(kind_ == SamplerKind::Independent ? mix64(pixel.pixel_key_ ^ (sample * 0x9e3779b97f4a7c15ULL)) : pixel.key_),
        shuffled_(sobol::nested_uniform_scramble(index_, pixel.shuffle_seed_)),
        tables_(pixel.tables_),
        x_(pixel.x_) {}
  /// For one sample alone (tests, tools); a renderer keeps one PixelSeeds per pixel.
  PixelSampler(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel, std::uint64_t sample)
      : PixelSampler(PixelSeeds(kind, seed, pixel), sample) {}

  float next1d() {
    const std::uint32_t d = dim_++;
    if (kind_ == SamplerKind::Independent) return independent(d);
    if (d < global_dimensions()) return global(d);
    return sobol::sample_1d(index_, scramble(d));
  }
  Point2 next2d() {
    const std::uint32_t d = dim_;
    dim_ += 2;
    if (kind_ == SamplerKind::Independent) return {independent(d), independent(d + 1)};
    if (d + 1 < global_dimensions()) return {global(d), global(d + 1)};
    Point2 p;
    sobol::sample_2d(index_, scramble(d), &p.x, &p.y);
    return p;
  }
  std::uint32_t dimension() const { return dim_; }
  void set_dimension(std::uint32_t d) { dim_ = d; }
  SamplerKind kind() const { return kind_; }

  /// 64 random bits for an independent stream (e.g. per-shading-point jitter), distinct per sample
  /// with either kind.
  std::uint64_t stream(std::uint32_t dim) const {
    const std::uint64_t per_sample = kind_ != SamplerKind::Independent ? std::uint64_t(index_) * 0xd1b54a32d192ed03ULL : 0;
    return mix64(key_ ^ mix64(0xa0761d6478bd642fULL + dim) ^ per_sample);
  }

 private:
  /// Dimensions taken from the pixel's point of the full Sobol sequence; the rest are padded pairs.
  /// Padded: only the pixel position (dimensions 0 and 1).
  std::uint32_t global_dimensions() const { return kind_ == SamplerKind::Padded ? 2u : std::uint32_t(sobol::kDimensions); }
  /// Uniform in [0, 1) with 24 random bits (never exactly 1).
  float independent(std::uint32_t dim) const {
    const std::uint64_t h = PixelSeeds::scramble_key(key_, dim);
    return float(h >> 40) * 0x1p-24f;
  }
  /// Dimension d of the pixel's shuffled point of the full Sobol sequence, Owen-scrambled.
  float global(std::uint32_t d) const {
    const std::uint32_t x = d < PixelSeeds::kCached ? x_[d] : scramble(d).x;
    return sobol::to_unit_float(sobol::scrambled_dim(tables_ + 128 * d, shuffled_, x));
  }
  sobol::Scramble scramble(std::uint32_t dim) const { return PixelSeeds::scramble(key_, dim); }

  SamplerKind kind_;
  std::uint32_t index_;
  std::uint64_t key_;
  std::uint32_t shuffled_;  // the sample index after the pixel's shuffle (full Sobol)
  std::uint32_t dim_ = 0;
  const std::uint32_t* tables_;                       // sobol::nibble_tables(0)
  std::array<std::uint32_t, PixelSeeds::kCached> x_;  // the pixel's first scramble seeds
};

}  // namespace envpis::render
