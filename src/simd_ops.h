// SPDX-License-Identifier: Apache-2.0
// Internal: a handful of operations written once for `float` (the scalar reference) and for
// std::experimental::simd<float, Abi> (SSE2 / AVX2 / AVX-512 lanes), so every kernel has one source.
// Included once per instruction set, inside that set's own namespace (ENVPIS_KERNEL_NS), so that no
// inline function compiled for AVX2 can be merged by the linker with its SSE2 or scalar twin. (A
// translation unit uses one set, so #pragma once holds.)
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <experimental/simd>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#ifndef ENVPIS_INLINE
#define ENVPIS_INLINE inline __attribute__((always_inline))
#endif

namespace envpis::detail::ENVPIS_KERNEL_NS::simd {

namespace stdx = std::experimental;

// ---- scalar ----
ENVPIS_INLINE float select(bool m, float a, float b) { return m ? a : b; }
ENVPIS_INLINE float load(const float* p) { return *p; }
ENVPIS_INLINE void store(float v, float* p) { *p = v; }
ENVPIS_INLINE float vsqrt(float a) { return std::sqrt(a); }
ENVPIS_INLINE float vabs(float a) { return std::fabs(a); }
ENVPIS_INLINE float vmin(float a, float b) { return std::min(a, b); }
ENVPIS_INLINE float vmax(float a, float b) { return std::max(a, b); }
ENVPIS_INLINE float vcopysign(float mag, float sgn) { return std::copysign(mag, sgn); }
ENVPIS_INLINE float lane_sum(float v) { return v; }
template <class V>
constexpr std::size_t lanes() {
  if constexpr (std::is_same_v<V, float>) return 1;
  else return V::size();
}

// ---- SIMD ----
template <class A>
using VF = stdx::simd<float, A>;
template <class A>
ENVPIS_INLINE VF<A> select(typename VF<A>::mask_type m, VF<A> a, VF<A> b) {
  VF<A> r = b;
  stdx::where(m, r) = a;
  return r;
}
template <class V>
ENVPIS_INLINE V load_v(const float* p) {
  return V(p, stdx::element_aligned);
}
template <class A>
ENVPIS_INLINE void store(VF<A> v, float* p) { v.copy_to(p, stdx::element_aligned); }
template <class A>
ENVPIS_INLINE VF<A> vsqrt(VF<A> a) { return stdx::sqrt(a); }
template <class A>
ENVPIS_INLINE float lane_sum(VF<A> v) { return stdx::reduce(v); }
template <class A>
ENVPIS_INLINE VF<A> vabs(VF<A> a) { return stdx::abs(a); }
template <class A>
ENVPIS_INLINE VF<A> vmin(VF<A> a, VF<A> b) { return stdx::min(a, b); }
template <class A>
ENVPIS_INLINE VF<A> vmax(VF<A> a, VF<A> b) { return stdx::max(a, b); }
template <class A>
ENVPIS_INLINE VF<A> vcopysign(VF<A> mag, VF<A> sgn) { return stdx::copysign(mag, sgn); }

// Coarse square root and reciprocal for the product weights: the hardware estimates alone (relative
// error below 1.5 * 2^-12, about 3.7e-4), several times the throughput of vsqrtps / vdivps. Enough:
// the weights only shape the distribution and pdf() reads the weights that were stored, so sampling
// and pdf stay exactly consistent. A Newton step each cost a quarter of the kernel's time.
// Scalar: exact (the reference the SIMD kernels are tested against).
ENVPIS_INLINE float vsqrt_fast(float x) { return std::sqrt(x); }
ENVPIS_INLINE float vrcp_fast(float x) { return 1.0f / x; }
template <class A>
ENVPIS_INLINE VF<A> rsqrt_estimate(VF<A> x) {
#if defined(__AVX512F__)
  if constexpr (sizeof(VF<A>) == 64) return VF<A>(_mm512_maskz_rsqrt14_ps(__mmask16(0xffff), static_cast<__m512>(x)));
#endif
#if defined(__AVX__)
  if constexpr (sizeof(VF<A>) == 32) return VF<A>(_mm256_rsqrt_ps(static_cast<__m256>(x)));
#endif
#if defined(__SSE2__)
  if constexpr (sizeof(VF<A>) == 16) return VF<A>(_mm_rsqrt_ps(static_cast<__m128>(x)));
#endif
  return VF<A>(1.0f) / stdx::sqrt(x);
}
template <class A>
ENVPIS_INLINE VF<A> rcp_estimate(VF<A> x) {
#if defined(__AVX512F__)
  if constexpr (sizeof(VF<A>) == 64) return VF<A>(_mm512_maskz_rcp14_ps(__mmask16(0xffff), static_cast<__m512>(x)));
#endif
#if defined(__AVX__)
  if constexpr (sizeof(VF<A>) == 32) return VF<A>(_mm256_rcp_ps(static_cast<__m256>(x)));
#endif
#if defined(__SSE2__)
  if constexpr (sizeof(VF<A>) == 16) return VF<A>(_mm_rcp_ps(static_cast<__m128>(x)));
#endif
  return VF<A>(1.0f) / x;
}
/// sqrt(x) for x >= 0: x / sqrt(x), with the estimate taken at max(x, 1e-30) so that x = 0 gives
/// 0 * 1e15 = 0 rather than 0 * inf.
template <class A>
ENVPIS_INLINE VF<A> vsqrt_fast(VF<A> x) {
  return x * rsqrt_estimate(vmax(x, VF<A>(1e-30f)));
}
/// 1 / x for x > 1e-30.
template <class A>
ENVPIS_INLINE VF<A> vrcp_fast(VF<A> x) {
  return rcp_estimate(x);
}

template <class V>
ENVPIS_INLINE V load_any(const float* p) {
  if constexpr (std::is_same_v<V, float>) return *p;
  else return load_v<V>(p);
}

/// atan(x) for x in [0, 1], about 1 ulp (Cephes-style range reduction + odd polynomial).
template <class V>
ENVPIS_INLINE V atan_unit(V x) {
  const auto big = x > V(0.41421356237f);  // tan(pi/8)
  const V t = select(big, (x - V(1.0f)) / (x + V(1.0f)), x);
  const V z = t * t;
  V p = V(8.05374449538e-2f) * z - V(1.38776856032e-1f);
  p = p * z + V(1.99777106478e-1f);
  p = p * z - V(3.33329491539e-1f);
  p = p * z * t + t;
  return select(big, p + V(0.78539816339744830962f), p);
}

/// atan2(y, x) in (-pi, pi] from atan_unit (scalar).
ENVPIS_INLINE float atan2_fast(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  float a = hi > 0 ? atan_unit(lo / hi) : 0.0f;
  if (ay > ax) a = 1.57079632679489661923f - a;
  if (x < 0) a = 3.14159265358979323846f - a;
  return std::copysign(a, y);
}

/// sin and cos of phi in [0, pi/2] (polynomials, ~1e-7 absolute).
template <class V>
ENVPIS_INLINE void sincos_quadrant(V phi, V& s, V& c) {
  // Reduce to [0, pi/4] by symmetry about pi/4.
  const auto hi = phi > V(0.78539816339744830962f);
  const V x = select(hi, V(1.57079632679489661923f) - phi, phi);
  const V x2 = x * x;
  V sp = V(-1.9515295891e-4f);
  sp = sp * x2 + V(8.3321608736e-3f);
  sp = sp * x2 - V(1.6666654611e-1f);
  const V sx = sp * x2 * x + x;
  V cp = V(2.443315711809948e-5f);
  cp = cp * x2 - V(1.388731625493765e-3f);
  cp = cp * x2 + V(4.166664568298827e-2f);
  const V cx = cp * x2 * x2 - V(0.5f) * x2 + V(1.0f);
  s = select(hi, cx, sx);
  c = select(hi, sx, cx);
}

}  // namespace envpis::detail::ENVPIS_KERNEL_NS::simd
