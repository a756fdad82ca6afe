// SPDX-License-Identifier: Apache-2.0
// Compiled with the default x86-64 baseline (SSE2): 4 float lanes.
#define ENVPIS_KERNEL_NS sse2
#include "kernels_impl.inl"

namespace envpis::detail {
const Kernels& kernels_sse2() {
  using V = std::experimental::native_simd<float>;
  static const Kernels k = sse2::make_kernels<V>("sse2");
  return k;
}
}  // namespace envpis::detail
