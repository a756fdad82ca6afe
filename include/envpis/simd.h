// SPDX-License-Identifier: Apache-2.0
// The instruction set of the library's vector kernels (the batched equal-area mapping and the product
// sampler's per-shading-point weights). Every kernel set computes the same function as the scalar
// reference (tests/test_product_sampler.cpp checks each one this CPU runs); the choice only trades
// speed, e.g. to keep 512-bit instructions off CPUs that lower their clock for them.
//
// The library never reads the environment: callers choose through ProductSamplerOptions::simd and the
// batched functions' argument. (The envpis command and the benchmarks read ENVPIS_SIMD as a
// command-line convenience and pass it on.)
#pragma once

#include <string>

namespace envpis {

enum class Simd {
  Best,    ///< the widest set this build has and this CPU runs
  Scalar,  ///< the scalar reference
  SSE2,
  AVX2,    ///< with FMA
  AVX512,  ///< F, DQ, VL
};

/// "best", "scalar", "sse2", "avx2", "avx512" (what ENVPIS_SIMD accepts). Throws Error otherwise.
Simd parse_simd(const std::string& name);
const char* to_string(Simd simd);
/// True when this build has the set and this CPU runs it (Best and Scalar always).
bool simd_supported(Simd simd);
/// The set that `simd` stands for on this CPU (Best -> the widest); throws Error when not supported.
Simd simd_resolve(Simd simd);
/// Lanes of a set (Best -> the widest's): 1, 4, 8 or 16.
int simd_width(Simd simd = Simd::Best);

}  // namespace envpis
