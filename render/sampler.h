// The random numbers of one pixel sample: independent uniform numbers, or Owen-scrambled Sobol points
// (render/sobol.h), the default.
//
// Dimensions are consumed in order by next1d() / next2d(); set_dimension() jumps to a fixed block
// (the integrator gives each path vertex its own, so a vertex's numbers do not depend on what earlier
// vertices consumed). Every value is a function of (kind, seed, pixel, sample index, dimension) only,
// so a pixel's samples never depend on which thread renders it or in which order tiles run.
//
// Sobol: each next2d() call is one padded pair, a 2D (0,2)-sequence over the pixel's sample indices
// (the samples 0 .. 2^m - 1 of a pixel are stratified in every elementary interval of area 2^-m);
// each next1d() call is a scrambled, shuffled van der Corput sequence. Pairs and pixels are
// decorrelated by their own hashed scrambles.
#pragma once

#include <cstdint>
#include <string>

#include "envpis/common.h"
#include "render/hash.h"
#include "render/sobol.h"

namespace envpis::render {

enum class SamplerKind { Independent, Sobol };
/// "independent" | "sobol"; throws Error otherwise.
SamplerKind parse_sampler(const std::string& s);
const char* to_string(SamplerKind k);

class PixelSampler {
 public:
  PixelSampler(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel, std::uint64_t sample)
      : kind_(kind),
        index_(static_cast<std::uint32_t>(sample)),
        key_(mix64(mix64(mix64(seed + 0x632be59bd9b4e019ULL) ^ pixel) ^
                   (kind == SamplerKind::Sobol ? 0 : sample * 0x9e3779b97f4a7c15ULL))) {}

  float next1d() {
    const std::uint32_t d = dim_++;
    if (kind_ == SamplerKind::Independent) return independent(d);
    return sobol::sample_1d(index_, scramble(d));
  }
  Point2 next2d() {
    const std::uint32_t d = dim_;
    dim_ += 2;
    if (kind_ == SamplerKind::Independent) return {independent(d), independent(d + 1)};
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
    const std::uint64_t per_sample = kind_ == SamplerKind::Sobol ? std::uint64_t(index_) * 0xd1b54a32d192ed03ULL : 0;
    return mix64(key_ ^ mix64(0xa0761d6478bd642fULL + dim) ^ per_sample);
  }

 private:
  /// Uniform in [0, 1) with 24 random bits (never exactly 1).
  float independent(std::uint32_t dim) const {
    const std::uint64_t h = mix64(key_ + (std::uint64_t(dim) + 1) * 0x9e3779b97f4a7c15ULL);
    return float(h >> 40) * 0x1p-24f;
  }
  /// The per-(seed, pixel, dimension) scrambles: the same for all samples of the pixel, as the
  /// sequence's stratification needs.
  sobol::Scramble scramble(std::uint32_t dim) const {
    const std::uint64_t a = mix64(key_ + (std::uint64_t(dim) + 1) * 0x9e3779b97f4a7c15ULL);
    const std::uint64_t b = mix64(a ^ 0x5851f42d4c957f2dULL);
    return {static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(a >> 32), static_cast<std::uint32_t>(b)};
  }

  SamplerKind kind_;
  std::uint32_t index_;
  std::uint64_t key_;
  std::uint32_t dim_ = 0;
};

}  // namespace envpis::render
