// SPDX-License-Identifier: Apache-2.0
// The SplitMix64 finalizer (Steele et al. 2014; Stafford's "mix64" variant): a 64-bit bijection whose
// output bits each depend on every input bit. The renderer's random numbers are chains of it, keyed on
// (seed, pixel, sample, dimension), so they never depend on thread or tile order.
#pragma once

#include <cstdint>

namespace envpis::render {

inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace envpis::render
