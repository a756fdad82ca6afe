// SPDX-License-Identifier: Apache-2.0
// Internal: the portal view's per-cell estimate (envpis/portals.h), one body for `float` (the scalar
// reference) and for every SIMD width: the top cells in PortalView::prepare and one cell's sub-cells in
// PortalView::subcell_fractions, through the kernel table. Included per instruction set inside
// ENVPIS_KERNEL_NS (see simd_ops.h).
#pragma once

#include <cstddef>
#include <experimental/simd>

#include "kernels.h"
#include "simd_ops.h"

namespace envpis::detail::ENVPIS_KERNEL_NS {

using namespace simd;

/// Share of a ball on the positive side of a plane at signed distance x (in radii): a smooth estimate
/// of a cone's share on one side of a plane (within 0.04 of the disk's share; see portals.h).
template <class V>
ENVPIS_INLINE V cut_share(V x) {
  x = vmin(vmax(x, V(-1.0f)), V(1.0f));
  return V(0.5f) + x * (V(0.75f) - V(0.25f) * x * x);
}

/// One cone (axis a, 1 / sin b, the outside and inside thresholds) against the four edge planes n[k]:
/// 0 outside some plane, 1 inside all, else the Cone estimate, at least min_partial (portals.h).
template <class V>
ENVPIS_INLINE V cone_plane_share(const float (&n)[4][3], V x, V y, V z, V inv_sin, V out_thr, V in_thr,
                                 float min_partial) {
  V lo = V(2.0f), share = V(1.0f);
  for (int k = 0; k < 4; ++k) {
    const V d = x * V(n[k][0]) + y * V(n[k][1]) + z * V(n[k][2]);
    lo = vmin(lo, d);
    share = share * cut_share(d * inv_sin);
  }
  const V own = select(lo < out_thr, V(0.0f), vmax(share, V(min_partial)));
  return select(lo >= in_thr, V(1.0f), own);
}

ENVPIS_INLINE bool any_lane(bool m) { return m; }
template <class M>
ENVPIS_INLINE bool any_lane(const M& m) {
  return stdx::any_of(m);
}

/// Every padded top cell against the `count` seen portals, one load of the cells for all of them. Per
/// portal, a cell whose cone misses the portal's bounding cone (a . g < cos(b + b_p), less a margin;
/// never for a wide portal, whose `near_bias` is large) gets 0, the others cone_plane_share; a vector
/// of cells none of which is near skips the planes. Writes v = min(1, sum of the shares) and full = 1
/// where one portal's share is 1 (else 0); returns whether any v is positive.
template <class V>
__attribute__((flatten)) bool portal_shares_t(const PortalCellArrays& c, const PortalPlanes* planes, int count,
                                               float* v, float* full) {
  constexpr std::size_t W = lanes<V>();
  V seen = V(0.0f);
  for (std::size_t i = 0; i < static_cast<std::size_t>(c.padded_count); i += W) {
    const V x = load_any<V>(c.ax + i), y = load_any<V>(c.ay + i), z = load_any<V>(c.az + i);
    const V cosb = load_any<V>(c.cosb + i), sinb = load_any<V>(c.sinb + i), big = load_any<V>(c.big + i);
    V sum = V(0.0f), whole = V(0.0f);
    for (int j = 0; j < count; ++j) {
      const PortalPlanes& p = planes[j];
      const V reach = cosb * V(p.cos_p) - sinb * V(p.sin_p);
      const V gap = x * V(p.g[0]) + y * V(p.g[1]) + z * V(p.g[2]) - reach + big + V(p.near_bias);
      if (!any_lane(gap >= V(0.0f))) continue;  // no cell near (most, for a window): every share 0
      const V share = select(gap >= V(0.0f),
                             cone_plane_share(p.n, x, y, z, load_any<V>(c.inv_sin + i), load_any<V>(c.out_thr + i),
                                              load_any<V>(c.in_thr + i), p.min_partial),
                             V(0.0f));
      sum = sum + share;
      whole = select(share >= V(1.0f), V(1.0f), whole);
    }
    store(vmin(V(1.0f), sum), v + i);  // the same as capping after each portal: the shares are >= 0
    store(whole, full + i);
    seen = vmax(seen, sum);
  }
  return any_lane(seen > V(0.0f));
}

}  // namespace envpis::detail::ENVPIS_KERNEL_NS
