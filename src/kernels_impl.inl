// Internal: kernel bodies, included once per instruction set with ENVPIS_KERNEL_NS and ENVPIS_VF set.
// Each is a template over V = float (the scalar reference) or a std::experimental::simd type.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <experimental/simd>

#include "kernels.h"
#include "simd_ops.h"

namespace envpis::detail::ENVPIS_KERNEL_NS {

using namespace simd;

template <class V>
ENVPIS_INLINE void square_to_sphere_one(V px, V py, V& x, V& y, V& z) {
  px = vmin(vmax(px, V(0.0f)), V(1.0f));
  py = vmin(vmax(py, V(0.0f)), V(1.0f));
  const V u = V(2.0f) * px - V(1.0f);
  const V v = V(2.0f) * py - V(1.0f);
  const V au = vabs(u), av = vabs(v);
  const V sd = V(1.0f) - (au + av);  // > 0 in the upper hemisphere's diamond
  const V r = V(1.0f) - vabs(sd);
  const V safe_r = select(r > V(0.0f), r, V(1.0f));
  const V phi = select(r > V(0.0f), (av - au) / safe_r + V(1.0f), V(1.0f)) * V(0.78539816339744830962f);
  V s, c;
  sincos_quadrant(phi, s, c);
  const V scale = r * vsqrt(vmax(V(2.0f) - r * r, V(0.0f)));
  x = vcopysign(c * scale, u);
  y = vcopysign(s * scale, v);
  z = vcopysign(V(1.0f) - r * r, sd);
}

template <class V>
ENVPIS_INLINE void sphere_to_square_one(V dx, V dy, V dz, V& pu, V& pv) {
  const V inv_len = V(1.0f) / vsqrt(dx * dx + dy * dy + dz * dz);
  dx = dx * inv_len;
  dy = dy * inv_len;
  dz = dz * inv_len;
  const V x = vabs(dx), y = vabs(dy), z = vabs(dz);
  // r = sqrt(1 - z), computed as sqrt((x^2 + y^2) / (1 + z)) to keep precision near the poles.
  const V r = vsqrt((x * x + y * y) / (V(1.0f) + z));
  const V a = vmax(x, y), b = vmin(x, y);
  const V ratio = select(a > V(0.0f), b / select(a > V(0.0f), a, V(1.0f)), V(0.0f));
  V phi = atan_unit(ratio) * V(0.63661977236758134308f);  // 2 / pi
  phi = select(x < y, V(1.0f) - phi, phi);
  V v = phi * r;
  V u = r - v;
  const auto south = dz < V(0.0f);
  const V su = select(south, V(1.0f) - v, u);
  const V sv = select(south, V(1.0f) - u, v);
  u = vcopysign(su, dx);
  v = vcopysign(sv, dy);
  pu = vmin(vmax((u + V(1.0f)) * V(0.5f), V(0.0f)), V(1.0f));
  pv = vmin(vmax((v + V(1.0f)) * V(0.5f), V(0.0f)), V(1.0f));
}

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

/// LobeParams broadcast to V.
template <class V>
struct LobeV {
  V nx, ny, nz, rx, ry, rz, tx, ty, tz, kd, kt, cr, mr, ct, mt;
  explicit LobeV(const LobeParams& p)
      : nx(p.n[0]), ny(p.n[1]), nz(p.n[2]), rx(p.r[0]), ry(p.r[1]), rz(p.r[2]), tx(p.t[0]), ty(p.t[1]),
        tz(p.t[2]), kd(p.kd), kt(p.kt), cr(p.cr), mr(p.mr), ct(p.ct), mt(p.mt) {}
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
  const V cR = closest_cos(l.rx * ax + l.ry * ay + l.rz * az, cb, sb);
  V value = ggx_like(cR, l.cr, l.mr);
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

template <class V, bool kTransmission, bool kDiffuse>
ENVPIS_INLINE void product_weights_impl(const CellArrays& cells, const LobeParams& p, float* out) {
  constexpr std::size_t W = lanes<V>();
  const LobeV<V> l(p);
  for (std::size_t i = 0; i < static_cast<std::size_t>(cells.padded_count); i += W) {
    const V value = proxy_cone_value<V, kTransmission, kDiffuse>(
        l, load_any<V>(cells.ax + i), load_any<V>(cells.ay + i), load_any<V>(cells.az + i),
        load_any<V>(cells.cosb + i), load_any<V>(cells.sinb + i));
    store(value * load_any<V>(cells.prob + i), out + i);
  }
}

template <class V>
__attribute__((flatten)) void product_weights_t(const CellArrays& cells, const LobeParams& p, float* out) {
  const bool transmission = p.kt > 0.0f || p.ct > 0.0f;
  const bool diffuse = p.kd > 0.0f || p.kt > 0.0f;
  if (transmission) {
    if (diffuse) product_weights_impl<V, true, true>(cells, p, out);
    else product_weights_impl<V, true, false>(cells, p, out);
  } else {
    if (diffuse) product_weights_impl<V, false, true>(cells, p, out);
    else product_weights_impl<V, false, false>(cells, p, out);
  }
}

template <class V>
__attribute__((flatten)) void square_to_sphere_n(std::size_t n, const float* u, const float* v, float* x, float* y, float* z) {
  constexpr std::size_t W = lanes<V>();
  std::size_t i = 0;
  for (; i + W <= n; i += W) {
    V vx, vy, vz;
    square_to_sphere_one(load_any<V>(u + i), load_any<V>(v + i), vx, vy, vz);
    store(vx, x + i);
    store(vy, y + i);
    store(vz, z + i);
  }
  for (; i < n; ++i) square_to_sphere_one<float>(u[i], v[i], x[i], y[i], z[i]);
}

template <class V>
__attribute__((flatten)) void sphere_to_square_n(std::size_t n, const float* x, const float* y, const float* z, float* u, float* v) {
  constexpr std::size_t W = lanes<V>();
  std::size_t i = 0;
  for (; i + W <= n; i += W) {
    V vu, vv;
    sphere_to_square_one(load_any<V>(x + i), load_any<V>(y + i), load_any<V>(z + i), vu, vv);
    store(vu, u + i);
    store(vv, v + i);
  }
  for (; i < n; ++i) sphere_to_square_one<float>(x[i], y[i], z[i], u[i], v[i]);
}

/// This instruction set's kernel table (V = float: the scalar reference).
template <class V>
Kernels make_kernels(const char* name) {
  return {name, static_cast<int>(lanes<V>()), square_to_sphere_n<V>, sphere_to_square_n<V>, product_weights_t<V>};
}

}  // namespace envpis::detail::ENVPIS_KERNEL_NS
