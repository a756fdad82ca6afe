// SPDX-License-Identifier: Apache-2.0
#include <cstring>
#include <string>

#include "envpis/common.h"
#include "envpis/simd.h"
#include "kernels.h"

namespace envpis::detail {

#if !defined(ENVPIS_HAVE_AVX2_KERNELS)
const Kernels* kernels_avx2() { return nullptr; }
#endif
#if !defined(ENVPIS_HAVE_AVX512_KERNELS)
const Kernels* kernels_avx512() { return nullptr; }
#endif

static bool cpu_has_avx2_fma() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

// libgcc's feature bits also require the OS to save the AVX-512 state (XCR0), not only the CPUID bits.
static bool cpu_has_avx512() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return cpu_has_avx2_fma() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512vl");
#else
  return false;
#endif
}

std::vector<const Kernels*> kernels_available() {
  std::vector<const Kernels*> k{&kernels_scalar(), &kernels_sse2()};
  if (kernels_avx2() && cpu_has_avx2_fma()) k.push_back(kernels_avx2());
  if (kernels_avx512() && cpu_has_avx512()) k.push_back(kernels_avx512());
  return k;
}

const Kernels* kernels_named(const char* name) {
  for (const Kernels* k : kernels_available())
    if (std::strcmp(name, k->name) == 0) return k;
  return nullptr;
}

const Kernels& kernels_for(Simd simd) {
  static const Kernels& widest = *kernels_available().back();
  if (simd == Simd::Best) return widest;
  if (simd == Simd::Scalar) return kernels_scalar();
  if (const Kernels* k = kernels_named(to_string(simd))) return *k;
  throw Error(std::string("SIMD instruction set ") + to_string(simd) + " is not available on this CPU or build");
}

}  // namespace envpis::detail

namespace envpis {

Simd parse_simd(const std::string& name) {
  for (Simd s : {Simd::Best, Simd::Scalar, Simd::SSE2, Simd::AVX2, Simd::AVX512})
    if (name == to_string(s)) return s;
  throw Error("unknown SIMD instruction set '" + name + "' (best, scalar, sse2, avx2, avx512)");
}

const char* to_string(Simd simd) {
  switch (simd) {
    case Simd::Best: return "best";
    case Simd::Scalar: return "scalar";
    case Simd::SSE2: return "sse2";
    case Simd::AVX2: return "avx2";
    case Simd::AVX512: return "avx512";
  }
  return "?";
}

bool simd_supported(Simd simd) {
  return simd == Simd::Best || simd == Simd::Scalar || detail::kernels_named(to_string(simd)) != nullptr;
}

Simd simd_resolve(Simd simd) { return parse_simd(detail::kernels_for(simd).name); }

int simd_width(Simd simd) { return detail::kernels_for(simd).width; }

}  // namespace envpis
