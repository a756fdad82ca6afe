// SPDX-License-Identifier: Apache-2.0
// Analytic spheres tested outside Embree (render/sphere.h, Scene::set_direct_sphere_limit): the same
// hits as Embree's point spheres, alone and mixed with meshes, from outside, inside and just off the
// surface, for unit and non-unit directions; degenerate rays give no hit.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "render/scenes.h"
#include "render/sphere.h"
#include "test_sky.h"

namespace envpis::render {
namespace {

Material lambert() {
  Material m;
  m.add(make_lambert({0.5f, 0.5f, 0.5f}));
  return m;
}

// Three overlapping spheres of different radii (one inside another's reach) and, with `floor`, a
// quad that cuts through two of them.
Scene spheres(int direct_limit, bool floor) {
  Scene s;
  const int m = s.add_material("grey", lambert(), false);
  s.add_sphere("a", {0, 0, 0}, 1.0f, m);
  s.add_sphere("b", {1.5f, 0.2f, 0}, 0.7f, m);
  s.add_sphere("c", {-0.4f, 1.1f, 0.3f}, 0.05f, m);
  if (floor) s.add_mesh("floor", make_quad({0, 0, -0.3f}, 3, 3), m);
  s.set_environment(test_sky());
  s.set_direct_sphere_limit(direct_limit);
  s.commit();
  return s;
}

Vec3 random_direction(std::mt19937& g) {
  std::normal_distribution<float> n;
  for (;;) {
    const Vec3 v{n(g), n(g), n(g)};
    if (dot(v, v) > 1e-6f) return normalize(v);
  }
}

// Rays that start far outside, inside the spheres, and just off a sphere's surface (as the integrator
// spawns them), some with directions scaled away from unit length and some with a finite tmax.
std::vector<Ray> rays(int n) {
  std::mt19937 g(7);
  std::uniform_real_distribution<float> u(0, 1);
  const Vec3 centres[] = {{0, 0, 0}, {1.5f, 0.2f, 0}, {-0.4f, 1.1f, 0.3f}};
  const float radii[] = {1.0f, 0.7f, 0.05f};
  std::vector<Ray> out;
  for (int i = 0; i < n; ++i) {
    Vec3 o;
    Vec3 d = random_direction(g);
    switch (i % 4) {
      case 0: o = random_direction(g) * 6.0f; d = normalize(Vec3{0.3f, 0.2f, 0} - o + random_direction(g) * 1.5f); break;
      case 1: o = random_direction(g) * (0.9f * u(g)); break;  // inside sphere a
      default: {                                                 // just off a surface, either side
        const int k = i % 3;
        const Vec3 n = random_direction(g);
        o = offset_ray_origin(centres[k] + n * radii[k], n, d);
      }
    }
    const float scale = i % 5 == 0 ? 3.0f : 1.0f;
    const float tmax = i % 7 == 0 ? 2.0f * u(g) : kInfinity;
    out.push_back({o, d * scale, tmax});
  }
  return out;
}

// Whether the ray passes within a relative 1e-3 of grazing some sphere: there the two tests may
// round to opposite sides, as two correct implementations can.
bool grazing(const Ray& r) {
  const Vec3 centres[] = {{0, 0, 0}, {1.5f, 0.2f, 0}, {-0.4f, 1.1f, 0.3f}};
  const float radii[] = {1.0f, 0.7f, 0.05f};
  const Vec3 d = normalize(r.direction);
  for (int k = 0; k < 3; ++k) {
    const Vec3 f = r.origin - centres[k];
    const Vec3 l = f - d * dot(f, d);
    if (std::fabs(std::sqrt(dot(l, l)) - radii[k]) < 1e-3f * radii[k]) return true;
  }
  return false;
}

void expect_same_hits(bool floor) {
  const Scene direct = spheres(Scene::kDirectSphereLimit, floor), bvh = spheres(0, floor);
  int compared = 0, hits = 0;
  for (const Ray& r : rays(20000)) {
    if (grazing(r)) continue;
    ++compared;
    SurfaceHit a, b;
    const bool ha = direct.intersect(r, &a), hb = bvh.intersect(r, &b);
    ASSERT_EQ(ha, hb) << "origin " << r.origin.x << " " << r.origin.y << " " << r.origin.z;
    EXPECT_EQ(direct.occluded(r.origin, r.direction, r.tmax), bvh.occluded(r.origin, r.direction, r.tmax));
    if (!ha) continue;
    ++hits;
    EXPECT_EQ(a.object, b.object);
    EXPECT_NEAR(a.t, b.t, 1e-4f * (1 + b.t));
    EXPECT_GT(dot(a.ng, b.ng), 0.99999f);
    EXPECT_NEAR(a.p.x, b.p.x, 1e-4f);
    EXPECT_NEAR(a.p.y, b.p.y, 1e-4f);
    EXPECT_NEAR(a.p.z, b.p.z, 1e-4f);
  }
  EXPECT_GT(compared, 19000);
  EXPECT_GT(hits, 8000);  // the set exercises hits, not only misses
}

TEST(DirectSpheres, SameHitsAsEmbreeForSpheresAlone) { expect_same_hits(false); }

TEST(DirectSpheres, SameHitsAsEmbreeMixedWithAMesh) { expect_same_hits(true); }

TEST(DirectSpheres, NearestOfSphereAndMeshEitherWay) {
  const Scene s = spheres(Scene::kDirectSphereLimit, true);
  SurfaceHit h;
  ASSERT_TRUE(s.intersect({{0, 0, 5}, {0, 0, -1}, kInfinity}, &h));  // sphere a's top before the floor
  EXPECT_EQ(h.object, 0);
  EXPECT_NEAR(h.t, 4.0f, 1e-4f);
  ASSERT_TRUE(s.intersect({{0, 0, -0.5f}, {0, 0, 1}, kInfinity}, &h));  // inside a: the floor first
  EXPECT_EQ(h.object, 3);
  EXPECT_NEAR(h.t, 0.2f, 1e-4f);
  ASSERT_TRUE(s.intersect({{0, 0, -5}, {0, 0, 1}, kInfinity}, &h));  // a's bottom below the floor
  EXPECT_EQ(h.object, 0);
  EXPECT_NEAR(h.t, 4.0f, 1e-4f);
  ASSERT_TRUE(s.intersect({{0, 0, 0}, {0, 0, 1}, kInfinity}, &h));  // from the centre: the far side
  EXPECT_EQ(h.object, 0);
  EXPECT_NEAR(h.t, 1.0f, 1e-5f);
  EXPECT_FALSE(s.intersect({{0, 0, 5}, {0, 0, -1}, 3.9f}, &h));  // tmax before the sphere
  EXPECT_FALSE(s.occluded({0, 0, 5}, {0, 0, -1}, 3.9f));
  EXPECT_TRUE(s.occluded({0, 0, 5}, {0, 0, -1}, 4.1f));
}

TEST(DirectSpheres, DegenerateRaysHitNothing) {
  const Scene s = spheres(Scene::kDirectSphereLimit, false);
  const float nan = std::nanf("");
  SurfaceHit h;
  EXPECT_FALSE(s.intersect({{0, 0, 5}, {0, 0, 0}, kInfinity}, &h));
  EXPECT_FALSE(s.intersect({{0, 0, 5}, {nan, 0, -1}, kInfinity}, &h));
  EXPECT_FALSE(s.intersect({{nan, 0, 5}, {0, 0, -1}, kInfinity}, &h));
  EXPECT_FALSE(s.occluded({0, 0, 5}, {0, 0, 0}));
  EXPECT_FALSE(s.occluded({0, 0, 5}, {nan, nan, nan}));
  float t = -1;
  EXPECT_FALSE(intersect_sphere({0, 0, 5}, {0, 0, 0}, {0, 0, 0}, 1, kInfinity, &t));
  EXPECT_FALSE(intersect_sphere({0, 0, 5}, {0, 1, 0}, {0, 0, 0}, 1, kInfinity, &t));  // a miss
  EXPECT_EQ(t, -1);
}

TEST(DirectSpheres, MoreThanTheLimitGoIntoEmbree) {
  Scene s;
  const int m = s.add_material("grey", lambert(), false);
  for (int i = 0; i <= Scene::kDirectSphereLimit; ++i) s.add_sphere("s" + std::to_string(i), {3.0f * i, 0, 0}, 1, m);
  s.set_environment(test_sky());
  s.commit();
  SurfaceHit h;
  ASSERT_TRUE(s.intersect({{3.0f * Scene::kDirectSphereLimit, 0, 5}, {0, 0, -1}, kInfinity}, &h));
  EXPECT_EQ(h.object, Scene::kDirectSphereLimit);
  EXPECT_NEAR(h.t, 4.0f, 1e-4f);
  EXPECT_THROW(s.set_direct_sphere_limit(0), Error);  // after commit()
}

}  // namespace
}  // namespace envpis::render
