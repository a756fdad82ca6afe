// SPDX-License-Identifier: Apache-2.0
// Internal: Clarberg's equal-area square <-> sphere mapping, one body for `float` (the scalar reference,
// also behind the public scalar functions) and for every SIMD width, plus its batched loops.
// Included per instruction set inside ENVPIS_KERNEL_NS (see simd_ops.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <experimental/simd>

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

}  // namespace envpis::detail::ENVPIS_KERNEL_NS
