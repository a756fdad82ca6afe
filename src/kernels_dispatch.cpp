#include <cstdlib>
#include <cstring>

#include "envpis/equal_area.h"
#include "kernels.h"

namespace envpis::detail {

#if !defined(ENVPIS_HAVE_AVX2_KERNELS)
const Kernels* kernels_avx2() { return nullptr; }
#endif

static bool cpu_has_avx2_fma() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

static const Kernels& choose() {
  const char* force = std::getenv("ENVPIS_SIMD");
  if (force && std::strcmp(force, "scalar") == 0) return kernels_scalar();
  if (force && std::strcmp(force, "sse2") == 0) return kernels_sse2();
  if (kernels_avx2() && cpu_has_avx2_fma()) return *kernels_avx2();
  return kernels_sse2();
}

const Kernels& kernels_best() {
  static const Kernels& k = choose();
  return k;
}

}  // namespace envpis::detail
