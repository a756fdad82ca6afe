// SPDX-License-Identifier: Apache-2.0
// Internal: one instruction set's kernel table, included once per set with ENVPIS_KERNEL_NS set (the
// scalar reference in equal_area.cpp, SSE2, AVX2, AVX-512 in their own translation units).
#include "equal_area_impl.h"
#include "kernels.h"
#include "portal_kernel_impl.h"
#include "proxy_lobe_impl.h"

namespace envpis::detail::ENVPIS_KERNEL_NS {

/// This instruction set's kernel table (V = float: the scalar reference).
template <class V>
Kernels make_kernels(const char* name) {
  return {name, static_cast<int>(lanes<V>()), square_to_sphere_n<V>, sphere_to_square_n<V>, product_weights_t<V>,
          floor_weights_t<V>, portal_shares_t<V>};
}

}  // namespace envpis::detail::ENVPIS_KERNEL_NS
