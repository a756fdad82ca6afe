#include <cstdlib>
#include <cstring>

#include "envpis/equal_area.h"
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

static const Kernels& choose() {
  if (const char* force = std::getenv("ENVPIS_SIMD"))
    if (const Kernels* k = kernels_named(force)) return *k;
  return *kernels_available().back();
}

const Kernels& kernels_best() {
  static const Kernels& k = choose();
  return k;
}

}  // namespace envpis::detail
