// SPDX-License-Identifier: Apache-2.0
// Compiled with -mavx2 -mfma (see src/CMakeLists.txt): 8 float lanes. Only called when the CPU has both.
#define ENVPIS_KERNEL_NS avx2
#include "kernels_impl.inl"

namespace envpis::detail {
const Kernels* kernels_avx2() {
  using V = std::experimental::native_simd<float>;
  static_assert(V::size() == 8, "kernels_avx2.cpp must be compiled with -mavx2 -mfma");
  static const Kernels k = avx2::make_kernels<V>("avx2");
  return &k;
}
}  // namespace envpis::detail
