// SPDX-License-Identifier: Apache-2.0
// Ray / sphere intersection for the scene's analytic spheres, tested outside Embree when a scene has
// few of them (render/scene.h, Scene::set_direct_sphere_limit): Embree's point-sphere primitive is
// built for millions of particles, and its dispatch costs far more than the test itself.
//
// The discriminant is formed from the ray's closest approach to the centre instead of b^2 - 4ac, and
// the roots from q = b + sign(b) sqrt(disc) (Haines et al., "Precision Improvements for Ray/Sphere
// Intersection", Ray Tracing Gems, 2019): no cancellation for distant or grazing rays.
#pragma once

#include "render/math.h"

#include <cmath>
#include <utility>

namespace envpis::render {

/// The nearest t in (0, tmax) with |o + t d - c| = r, if any. d need not be unit; a zero or
/// non-finite d or o gives no hit.
inline bool intersect_sphere(Vec3 o, Vec3 d, Vec3 c, float r, float tmax, float* t) {
  const Vec3 f = o - c;
  const float a = dot(d, d);
  const float b = -dot(f, d);
  const Vec3 l = f + d * (b / a);  // closest approach of the line to the centre
  const float disc = a * (r * r - dot(l, l));
  if (!(disc >= 0)) return false;  // a miss, or NaN from a zero direction
  const float q = b + std::copysign(std::sqrt(disc), b);
  float t0 = (dot(f, f) - r * r) / q, t1 = q / a;
  if (t0 > t1) std::swap(t0, t1);
  const float th = t0 > 0 ? t0 : t1;
  if (!(th > 0) || !(th < tmax)) return false;
  *t = th;
  return true;
}

}  // namespace envpis::render
