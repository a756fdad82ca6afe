// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "chi2.h"
#include "envpis/equal_area.h"

using namespace envpis;

namespace {

// An independent double-precision implementation of Clarberg's mapping (with std::atan2, no
// polynomials), the reference the library's float versions are compared with.
struct D3 {
  double x, y, z;
};
D3 ref_square_to_sphere(double px, double py) {
  const double u = 2 * px - 1, v = 2 * py - 1, au = std::abs(u), av = std::abs(v);
  const double sd = 1 - (au + av), r = 1 - std::abs(sd);
  const double phi = (r == 0 ? 1 : (av - au) / r + 1) * M_PI / 4;
  const double z = std::copysign(1 - r * r, sd);
  const double s = r * std::sqrt(std::max(0.0, 2 - r * r));
  return {std::copysign(std::cos(phi), u) * s, std::copysign(std::sin(phi), v) * s, z};
}

double angle_between(Vec3 a, D3 b) {
  const double la = std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
  const double c = (a.x * b.x + a.y * b.y + a.z * b.z) / la;
  const double cx = a.y * b.z - a.z * b.y, cy = a.z * b.x - a.x * b.z, cz = a.x * b.y - a.y * b.x;
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz) / la, c);
}

std::vector<double> grid_coords(int n) {
  std::vector<double> c;
  for (int i = 0; i <= n; ++i) c.push_back(double(i) / n);  // includes 0, 0.5, 1 and the fold lines
  for (double e : {1e-7, 1e-4, 0.25 - 1e-6, 0.25 + 1e-6, 0.5 - 1e-7, 0.5 + 1e-7, 0.75, 1 - 1e-7}) c.push_back(e);
  return c;
}

}  // namespace

TEST(EqualArea, ForwardMatchesDoubleReference) {
  const auto c = grid_coords(256);
  double worst = 0;
  for (double y : c)
    for (double x : c) {
      const Vec3 d = equal_area_square_to_sphere({float(x), float(y)});
      EXPECT_NEAR(length(d), 1.0f, 2e-6f);
      worst = std::max(worst, angle_between(d, ref_square_to_sphere(float(x), float(y))));
    }
  EXPECT_LT(worst, 2e-6) << "worst angular error (radians)";
}

TEST(EqualArea, RoundTripDenseGridIncludingEdgesFoldsAndPoles) {
  const auto c = grid_coords(512);
  double worst_dir = 0, worst_square = 0;
  for (double y : c)
    for (double x : c) {
      const Point2 p{float(x), float(y)};
      const Vec3 d = equal_area_square_to_sphere(p);
      const Point2 q = equal_area_sphere_to_square(d);
      // Always: the round trip reproduces the direction (edge points have two preimages).
      worst_dir = std::max(worst_dir, angle_between(equal_area_square_to_sphere(q), D3{d.x, d.y, d.z}));
      const bool on_edge = x == 0 || x == 1 || y == 0 || y == 1;
      if (!on_edge) worst_square = std::max<double>(worst_square, std::max(std::abs(q.x - p.x), std::abs(q.y - p.y)));
    }
  EXPECT_LT(worst_dir, 2e-6);
  EXPECT_LT(worst_square, 2e-6);
  // Poles: north at the centre, south at the four corners.
  const Point2 n = equal_area_sphere_to_square({0, 0, 1});
  EXPECT_NEAR(n.x, 0.5f, 1e-6f);
  EXPECT_NEAR(n.y, 0.5f, 1e-6f);
  const Point2 s = equal_area_sphere_to_square({0, 0, -1});
  EXPECT_TRUE((s.x == 0 || s.x == 1) && (s.y == 0 || s.y == 1)) << s.x << "," << s.y;
  for (Point2 corner : {Point2{0, 0}, Point2{1, 0}, Point2{0, 1}, Point2{1, 1}})
    EXPECT_NEAR(equal_area_square_to_sphere(corner).z, -1.0f, 1e-6f);
  EXPECT_NEAR(equal_area_square_to_sphere({0.5f, 0.5f}).z, 1.0f, 1e-6f);
  // The diamond |2x-1|+|2y-1| = 1 is the equator.
  for (double t : c) {
    const Vec3 d = equal_area_square_to_sphere({float(t / 2), float(0.5 + t / 2)});
    EXPECT_NEAR(d.z, 0.0f, 2e-6f);
  }
}

TEST(EqualArea, NearPolePrecision) {
  // Directions within 1e-3 rad of each pole survive the round trip with small angular error.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < 10000; ++i) {
    const double t = 1e-3 * U(rng), ph = 2 * M_PI * U(rng), zs = i % 2 ? 1 : -1;
    const D3 d{std::sin(t) * std::cos(ph), std::sin(t) * std::sin(ph), zs * std::cos(t)};
    const Vec3 back = equal_area_square_to_sphere(equal_area_sphere_to_square({float(d.x), float(d.y), float(d.z)}));
    EXPECT_LT(angle_between(back, d), 2e-5) << i;
  }
}

TEST(EqualArea, WrapMatchesSphereNeighbours) {
  // A texel just outside an edge, after wrapping, must be the texel on the sphere beside it.
  const int n = 48;
  for (int i = 0; i < n; ++i)
    for (int side = 0; side < 4; ++side) {
      int x = side == 0 ? -1 : side == 1 ? n : i;
      int y = side == 2 ? -1 : side == 3 ? n : i;
      const float ox = (x + 0.5f) / n, oy = (y + 0.5f) / n;  // outside point
      // the edge point it touches
      const float ex = std::clamp(ox, 0.0f, 1.0f), ey = std::clamp(oy, 0.0f, 1.0f);
      ASSERT_TRUE(equal_area_wrap(n, x, y));
      const Vec3 e = equal_area_square_to_sphere({ex, ey});
      const Vec3 w = equal_area_square_to_sphere({(x + 0.5f) / n, (y + 0.5f) / n});
      // the wrapped texel centre is half a texel from the edge, like the outside point was
      EXPECT_GT(dot(e, w), std::cos(2.5f * kPi / n)) << "side " << side << " i " << i;
    }
  int x = -5 * n, y = 0;
  EXPECT_FALSE(equal_area_wrap(n, x, y));
}

TEST(EqualArea, UniformSphereSamplesFillTheTopCellsEqually) {
  // Equal area: uniform directions land in each of the 12 x 12 cells with probability 1/144.
  test::Chi2Options opt;
  opt.bins = 12;
  opt.sub = 4;
  opt.samples = 500000;
  opt.seed = 3;
  const auto r = test::chi2_test(
      [](float u1, float u2) -> std::optional<Vec3> {
        const float z = 1 - 2 * u1, phi = 2 * kPi * u2, s = std::sqrt(std::max(0.0f, 1 - z * z));
        return Vec3{s * std::cos(phi), s * std::sin(phi), z};
      },
      [](Vec3) { return 1.0 / (4 * M_PI); }, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-6);
}

TEST(EqualArea, SimdMatchesScalar) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> U(0, 1);
  const std::size_t n = 10007;  // not a multiple of the lane count: the tail path runs too
  std::vector<float> u(n), v(n), x(n), y(n), z(n), bu(n), bv(n);
  for (std::size_t i = 0; i < n; ++i) {
    u[i] = i < 8 ? float(i % 2) : U(rng);
    v[i] = i < 8 ? float(i / 4) : U(rng);
  }
  equal_area_square_to_sphere(n, u.data(), v.data(), x.data(), y.data(), z.data());
  equal_area_sphere_to_square(n, x.data(), y.data(), z.data(), bu.data(), bv.data());
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = equal_area_square_to_sphere({u[i], v[i]});
    ASSERT_NEAR(x[i], d.x, 1e-6f) << i;
    ASSERT_NEAR(y[i], d.y, 1e-6f) << i;
    ASSERT_NEAR(z[i], d.z, 1e-6f) << i;
    const Point2 p = equal_area_sphere_to_square({x[i], y[i], z[i]});
    ASSERT_NEAR(bu[i], p.x, 1e-6f) << i;
    ASSERT_NEAR(bv[i], p.y, 1e-6f) << i;
  }
  EXPECT_GE(simd_width(), 1);
  std::printf("SIMD path: %s (%d lanes)\n", to_string(simd_resolve(Simd::Best)), simd_width());
}
