// SPDX-License-Identifier: Apache-2.0
// Internal: the proxy lobes' shapes evaluated over a top cell's bounding cone (kernels.h, LobeParams),
// one body for `float` (PreparedProxy::eval_cone) and for every SIMD width, and the product weights
// loop over the cells. Included per instruction set inside ENVPIS_KERNEL_NS (see simd_ops.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <experimental/simd>

#include "envpis/common.h"
#include "kernels.h"
#include "simd_ops.h"

namespace envpis::detail::ENVPIS_KERNEL_NS {

using namespace simd;

/// cos of the angle between `axis` and the direction of the cone (axis a, half-angle b) closest to it:
/// max(0, t - b) where cos t = c.
template <class V>
ENVPIS_INLINE V closest_cos(V c, V cosb, V sinb) {
  const V s = vsqrt_fast(vmax(V(1.0f) - c * c, V(0.0f)));
  return select(c >= cosb, V(1.0f), c * cosb + s * sinb);
}

/// The simplified GGX lobe coef / (1 + m c^2)^2 for c > 0; beyond 90 degrees from the lobe axis it keeps
/// its value at 90 degrees (the lobe's tail, coef = w a^2 / pi) instead of rising again, so that every
/// direction on the lobe's side of the surface keeps a small positive weight (true GGX lobes reach the
/// whole hemisphere through the half-vector, e.g. back-scattering at grazing views).
template <class V>
ENVPIS_INLINE V ggx_like(V c, V coef, V m) {
  const V cp = vmax(c, V(0.0f));
  const V d = V(1.0f) + m * cp * cp;  // >= a'^2 >= 1e-6
  return coef * vrcp_fast(d * d);
}

/// The half-vector lobe coef / (1 + m (N.h)^2)^2, h = (wo + w) / |wo + w|, for a direction w with N.w = cn
/// and R.w = cr: wo.w = 2 co cn - cr (R = 2 co N - wo), so (N.h)^2 = (co + cn)^2 / (2 + 2 wo.w). Where
/// N.h would be negative (w far below the horizon) it keeps its value at N.h = 0, the tail coef, as
/// ggx_like does beyond 90 degrees. Written as coef s2^2 / (s2 + m nh^2)^2 with nh = N.(wo + w), s2 = |wo + w|^2, so that the one estimated
/// reciprocal comes last: through (N.h)^2 its error would be multiplied by 1 / a^2 at the peak.
template <class V>
ENVPIS_INLINE V ggx_half(V cn, V cr, V co, V coef, V m) {
  const V s2 = vmax(V(2.0f) + V(4.0f) * co * cn - V(2.0f) * cr, V(1e-6f));
  const V nh = vmax(co + cn, V(0.0f));
  const V d = s2 + m * vmin(nh * nh, s2);  // (N.h)^2 <= 1
  const V q = s2 * vrcp_fast(d);
  return coef * q * q;
}

/// E[max(0, X)] for X with mean m and variance v, as the smooth maximum (m + sqrt(m^2 + 2 v / pi)) / 2:
/// exact for |m| >> sqrt(v) and at m = 0 for a normal X, never 0 while v > 0 (a cell straddling the
/// horizon keeps a weight even when its mean is below it).
template <class V>
ENVPIS_INLINE V mean_positive_part(V m, V v) {
  // For m < 0 as v / (2 (r - m)), r = sqrt(m^2 + v): the same value without the cancellation that
  // would magnify the square root estimate's error.
  const V r = vsqrt_fast(m * m + v);
  return select(m >= V(0.0f), V(0.5f) * (m + r), V(0.5f) * v * vrcp_fast(r - m));
}

/// LobeParams broadcast to V.
template <class V>
struct LobeV {
  V nx, ny, nz, rx, ry, rz, tx, ty, tz, kd, kt, cr, mr, ct, mt, co;
  bool half;
  explicit LobeV(const LobeParams& p)
      : nx(p.n[0]), ny(p.n[1]), nz(p.n[2]), rx(p.r[0]), ry(p.r[1]), rz(p.r[2]), tx(p.t[0]), ty(p.t[1]),
        tz(p.t[2]), kd(p.kd), kt(p.kt), cr(p.cr), mr(p.mr), ct(p.ct), mt(p.mt), co(p.co), half(p.half != 0) {}
};

/// The proxy's value for a cone (axis a, half-angle b): every lobe evaluated at the cone's direction
/// closest to its axis. kTransmission = false skips the lobes below the surface (translucent and
/// refraction), for the common opaque case; it must only be used when both their weights are 0.
/// kDiffuse = false skips the cosine lobes (diffuse and translucent); only when both their weights are 0.
///
/// The cone reaches above the surface (some direction at less than 90 degrees from N) exactly when
/// angle(N, a) < 90 + b, i.e. N.a > cos(90 + b) = -sin b; below it when N.a < sin b. The gates test that
/// directly, so the sine of angle(N, a) is only computed for the cosine lobes' values.
template <class V, bool kTransmission = true, bool kDiffuse = true>
ENVPIS_INLINE V proxy_cone_value(const LobeV<V>& l, V ax, V ay, V az, V cb, V sb) {
  const V cn = l.nx * ax + l.ny * ay + l.nz * az;
  const V ca = l.rx * ax + l.ry * ay + l.rz * az;
  V value;
  if (l.half) {
    // At the cone's direction closest to R: R itself inside the cone, else the axis turned by b towards
    // R, whose N.w is (sin(t - b) N.a + sin b N.R) / sin t for t = angle(a, R).
    // (Exact square root and division: near the peak the lobe magnifies errors in N.w by 1 / a^2.)
    const V st = vsqrt(vmax(V(1.0f) - ca * ca, V(0.0f)));
    const V cn_near = ((st * cb - ca * sb) * cn + sb * l.co) / vmax(st, V(1e-6f));
    const auto inside = ca >= cb;
    value = ggx_half(select(inside, l.co, cn_near), select(inside, V(1.0f), ca * cb + st * sb), l.co, l.cr, l.mr);
  } else {
    value = ggx_like(closest_cos(ca, cb, sb), l.cr, l.mr);
  }
  V sn(0.0f);
  if constexpr (kDiffuse) {
    // N and -N make supplementary angles with the axis: one sine serves both.
    sn = vsqrt_fast(vmax(V(1.0f) - cn * cn, V(0.0f)));
    value = value + l.kd * select(cn >= cb, V(1.0f), cn * cb + sn * sb);  // towards N
  }
  value = select(cn > -sb, value, V(0.0f));
  if constexpr (kTransmission) {
    const V cT = closest_cos(l.tx * ax + l.ty * ay + l.tz * az, cb, sb);
    V below = ggx_like(cT, l.ct, l.mt);
    if constexpr (kDiffuse) below = below + l.kt * select(-cn >= cb, V(1.0f), sn * sb - cn * cb);  // towards -N
    value = value + select(cn < sb, below, V(0.0f));
  }
  return value;
}

/// The proxy's estimate for a cell from its moments (LobeParams::moments): the glossy lobes at the cell's
/// importance-weighted mean direction m (unit), the cosine lobes as the mean of max(0, cos) over the cell
/// from m and the cell's spread s = E[1 - w.m]. The cone (axis a, sine of its half-angle sb) only decides
/// which side of the surface the cell reaches, with the same gates as proxy_cone_value, and no lobe is 0
/// where it passes them, so the two estimates are positive for exactly the same cells.
template <class V, bool kTransmission = true, bool kDiffuse = true>
ENVPIS_INLINE V proxy_moment_value(const LobeV<V>& l, V ax, V ay, V az, V sb, V mx, V my, V mz, V spread) {
  const V cn = l.nx * ax + l.ny * ay + l.nz * az;
  // N.w over the cell: mean (1 - s) N.m exactly (N.w is linear in w); variance about s sin^2(N, m) (s is
  // the per-axis angular variance, taken along the direction in which N.w changes).
  const V cm = l.nx * mx + l.ny * my + l.nz * mz;
  const V mean_n = (V(1.0f) - spread) * cm;
  const V var_n = spread * vmax(V(1.0f) - cm * cm, V(0.0f));
  const V cr = l.rx * mx + l.ry * my + l.rz * mz;
  V value;
  if (l.half) {
    // The half-vector lobe at m, times the share of the cell above the horizon (a linear ramp in N.w
    // between one standard deviation either side of 0), at least 2%: unlike the mirror lobe it is large
    // just below the horizon, where the light sample is wasted.
    const V up = vmin(vmax(V(0.5f) + V(0.5f) * mean_n * vrcp_fast(vsqrt_fast(var_n) + V(1e-4f)), V(0.0f)), V(1.0f));
    value = ggx_half(cm, cr, l.co, l.cr, l.mr) * vmax(up, V(0.02f));
  } else {
    value = ggx_like(cr, l.cr, l.mr);
  }
  V mean_cos(0.0f), var_cos(0.0f);
  if constexpr (kDiffuse) {
    // The cosine lobes: E[max(0, N.w)] from that mean and variance, plus a little variance so that it
    // is never 0.
    mean_cos = mean_n;
    var_cos = V(2.0f * kInvPi) * var_n + V(1e-6f);
    value = value + l.kd * mean_positive_part(mean_cos, var_cos);
  }
  value = select(cn > -sb, value, V(0.0f));
  if constexpr (kTransmission) {
    V below = ggx_like(l.tx * mx + l.ty * my + l.tz * mz, l.ct, l.mt);
    if constexpr (kDiffuse) below = below + l.kt * mean_positive_part(-mean_cos, var_cos);
    value = value + select(cn < sb, below, V(0.0f));
  }
  return value;
}

// Returns the weights' total, summed in the lanes as they are written: the sampler needs it for the
// floor, and this spares it a second pass over the weights (DiscreteDistribution2D::sum) per shading point.
template <class V, bool kTransmission, bool kDiffuse, bool kMoments>
ENVPIS_INLINE float product_weights_impl(const CellArrays& cells, const LobeParams& p, float* out) {
  constexpr std::size_t W = lanes<V>();
  const LobeV<V> l(p);
  V total(0.0f);
  for (std::size_t i = 0; i < static_cast<std::size_t>(cells.padded_count); i += W) {
    V value;
    if constexpr (kMoments)
      value = proxy_moment_value<V, kTransmission, kDiffuse>(
          l, load_any<V>(cells.ax + i), load_any<V>(cells.ay + i), load_any<V>(cells.az + i),
          load_any<V>(cells.sinb + i), load_any<V>(cells.mx + i), load_any<V>(cells.my + i),
          load_any<V>(cells.mz + i), load_any<V>(cells.spread + i));
    else
      value = proxy_cone_value<V, kTransmission, kDiffuse>(
          l, load_any<V>(cells.ax + i), load_any<V>(cells.ay + i), load_any<V>(cells.az + i),
          load_any<V>(cells.cosb + i), load_any<V>(cells.sinb + i));
    const V w = value * load_any<V>(cells.prob + i);
    total = total + w;
    store(w, out + i);
  }
  return lane_sum(total);
}

template <class V, bool kMoments>
ENVPIS_INLINE float product_weights_lobes(const CellArrays& cells, const LobeParams& p, float* out) {
  const bool transmission = p.kt > 0.0f || p.ct > 0.0f;
  const bool diffuse = p.kd > 0.0f || p.kt > 0.0f;
  if (transmission) {
    if (diffuse) return product_weights_impl<V, true, true, kMoments>(cells, p, out);
    return product_weights_impl<V, true, false, kMoments>(cells, p, out);
  }
  if (diffuse) return product_weights_impl<V, false, true, kMoments>(cells, p, out);
  return product_weights_impl<V, false, false, kMoments>(cells, p, out);
}

template <class V>
__attribute__((flatten)) float product_weights_t(const CellArrays& cells, const LobeParams& p, float* out) {
  return p.moments ? product_weights_lobes<V, true>(cells, p, out) : product_weights_lobes<V, false>(cells, p, out);
}

// The environment floor on product weights w (ProductSampler): a positive w becomes max(w a, r e),
// the rest stays as it is. Element by element, so every width gives the scalar loop's bits.
template <class V>
void floor_weights_t(float* w, const float* e, int count, float a, float r) {
  constexpr std::size_t W = lanes<V>();
  const std::size_t n = static_cast<std::size_t>(count);
  std::size_t i = 0;
  for (; i + W <= n; i += W) {
    const V wv = load_any<V>(w + i);
    store(select(wv > V(0.0f), vmax(wv * V(a), V(r) * load_any<V>(e + i)), wv), w + i);
  }
  for (; i < n; ++i) w[i] = w[i] > 0.0f ? std::max(w[i] * a, r * e[i]) : w[i];
}

}  // namespace envpis::detail::ENVPIS_KERNEL_NS
