// SPDX-License-Identifier: Apache-2.0
// Small geometric helpers of the renderer, on top of the library's Vec3 / Rgb value types.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "envpis/common.h"

namespace envpis::render {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

inline Vec3 mul(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline float max_abs_component(Vec3 v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }
inline float max_component(Rgb c) { return std::max({c.r, c.g, c.b}); }
inline bool is_finite(Rgb c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }
inline bool is_black(Rgb c) { return !(c.r != 0 || c.g != 0 || c.b != 0); }
inline Rgb operator/(Rgb c, float s) { return c * (1.0f / s); }
inline Rgb& operator+=(Rgb& a, Rgb b) { return a = a + b; }
inline Rgb& operator*=(Rgb& a, Rgb b) { return a = a * b; }
inline Rgb& operator*=(Rgb& a, float s) { return a = a * s; }

/// An orthonormal frame around a unit normal n (Duff et al. 2017, "Building an Orthonormal Basis,
/// Revisited"): local +Z is n.
struct Frame {
  Vec3 s, t, n;
  Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  explicit Frame(Vec3 normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
  }
  Vec3 to_local(Vec3 v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(Vec3 v) const { return s * v.x + t * v.y + n * v.z; }
};

struct Ray {
  Vec3 origin;
  Vec3 direction;  ///< unit length
  float tmax = kInfinity;
};

/// Origin for a ray leaving surface point p towards the side of geometric normal ng that `dir`
/// points to; the offset scales with the magnitude of p so that float round-off in the hit point
/// never puts the origin on the wrong side.
inline Vec3 offset_ray_origin(Vec3 p, Vec3 ng, Vec3 dir) {
  const float eps = 1e-4f * (1.0f + max_abs_component(p));
  return dot(dir, ng) >= 0 ? p + ng * eps : p - ng * eps;
}

}  // namespace envpis::render
