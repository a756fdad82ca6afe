// SPDX-License-Identifier: Apache-2.0
// Compiled with -mavx512f -mavx512dq -mavx512vl -mfma (see src/CMakeLists.txt): 16 float lanes. Only
// called when the CPU has them.
#define ENVPIS_KERNEL_NS avx512
#include "kernels_impl.inl"

namespace envpis::detail {
const Kernels* kernels_avx512() {
  using V = std::experimental::native_simd<float>;
  static_assert(V::size() == 16, "kernels_avx512.cpp must be compiled with -mavx512f");
  static const Kernels k = avx512::make_kernels<V>("avx512");
  return &k;
}
}  // namespace envpis::detail
