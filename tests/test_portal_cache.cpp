// SPDX-License-Identifier: Apache-2.0
// ProductCache through portals (envpis/product_cache.h): shading points whose key (now with the point
// p rounded) is the same share one PortalView and one prepared product, and that distribution is the
// one prepared afresh at the key's rounded point, whatever the cache held before. So a light sample
// drawn at one point has, at any other point of the same key, exactly the density it was drawn with
// (MIS stays exact), and the result does not depend on the order of the points or the cache's size.
// Where the key's point sees no portal, the shading point is prepared exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "chi2.h"
#include "test_util.h"

using namespace envpis;
using namespace envpis::test;

namespace {

// The room of tests/test_portals.cpp: the box [-2, 2] x [-2, 2] x [0, 3], an east window and a skylight.
Quad quad(Vec3 c, Vec3 u, Vec3 v) { return {{c - u - v, c + u - v, c + u + v, c - u + v}}; }
Portals room_portals() {
  return Portals({quad({2, 0, 1.5f}, {0, 0.8f, 0}, {0, 0, 0.5f}), quad({0, 0, 3}, {0.5f, 0, 0}, {0, 0.5f, 0})});
}

BsdfProxy plastic(float alpha) {
  BsdfProxy b;
  b.add_diffuse(0.5f);
  b.add_reflection(0.5f, alpha);
  return b;
}

struct Point {
  Vec3 p, n, wo;
  BsdfProxy proxy;
};

// The samples of a few pixels: tight clusters of points (1 mm) on the floor and a wall, in random order.
std::vector<Point> clustered_points(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(-1, 1);
  const std::vector<Point> centres{
      {{-1, 0.5f, 0.001f}, {0, 0, 1}, normalize(Vec3{-1, -1, 1}), plastic(0.1f)},
      {{0.3f, -1.2f, 0.001f}, {0, 0, 1}, normalize(Vec3{0.2f, -1, 0.6f}), plastic(0.3f)},
      {{-1.999f, 0.4f, 1.2f}, {1, 0, 0}, normalize(Vec3{1, 0.3f, 0.2f}), plastic(0.05f)},
      {{0.5f, 1.5f, 0.001f}, {0, 0, 1}, normalize(Vec3{0, -1, 1}), plastic(0.5f)},
  };
  std::vector<Point> out;
  for (int i = 0; i < count; ++i) {
    Point q = centres[static_cast<std::size_t>(rng() % centres.size())];
    q.p = q.p + Vec3{U(rng), U(rng), 0} * 0.001f;
    q.wo = normalize(q.wo + Vec3{U(rng), U(rng), U(rng)} * 0.001f);
    out.push_back(q);
  }
  return out;
}

ProductCacheOptions cache_options(int entries) {
  ProductCacheOptions o;
  o.resolution = 128;
  o.entries = entries;
  o.position_step = 0.02f;
  return o;
}

}  // namespace

// Fails if a slot were prepared at the first point that missed (not its key's point), or if a point
// read another key's slot: the one-slot cache re-prepares for every cluster change, the large one
// keeps them all, and both must give the fresh sampler's samples and densities bit for bit.
TEST(ProductCachePortals, SharedSamplerIsTheSamplerOfTheRoundedPoint) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  const Portals portals = room_portals();
  const ProductSamplerOptions so = refined_sampler();
  ProductCache small(table, portals, so, cache_options(1)), large(table, portals, so, cache_options(16));
  ProductSampler fresh(table, so);
  PortalView view(table, portals);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> U(0, 1);
  const auto points = clustered_points(200, 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& q = points[i];
    const ProductSampler& a = small.prepare(q.p, q.n, q.wo, q.proxy);
    const ProductSampler& b = large.prepare(q.p, q.n, q.wo, q.proxy);
    const ProductCache::Rounded r = small.round(q.p, q.n, q.wo, q.proxy);
    ASSERT_TRUE(view.prepare(r.p));
    ASSERT_TRUE(fresh.prepare(r.n, r.wo, r.proxy, &view));
    for (int k = 0; k < 6; ++k) {
      const Point2 u{U(rng), U(rng)};
      const DirectionSample sf = fresh.sample(u), sa = a.sample(u), sb = b.sample(u);
      ASSERT_GT(sf.pdf, 0.0f);
      ASSERT_EQ(sf.pdf, sa.pdf);
      ASSERT_EQ(sf.pdf, sb.pdf);
      ASSERT_EQ(sf.direction.x, sb.direction.x);
      const Vec3 d = random_direction(rng);
      ASSERT_EQ(fresh.pdf(d), a.pdf(d));
      ASSERT_EQ(fresh.pdf(d), b.pdf(d));
    }
  }
  EXPECT_GT(large.hits(), 150u) << large.misses();
  EXPECT_LT(2 * small.hits(), large.hits()) << small.hits();
  EXPECT_EQ(large.exact_points(), 0u);
}

// MIS reads the density at the BSDF sample's vertex: a direction drawn at one point has, at another
// point of the same key (the next sample of the pixel), exactly the density it was drawn with.
TEST(ProductCachePortals, PdfAtAnotherPointOfTheKeyIsTheSampledDensity) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  ProductCache cache(table, room_portals(), refined_sampler(), cache_options(4));
  const Vec3 n{0, 0, 1}, wo = normalize(Vec3{-1, -0.5f, 1});
  const BsdfProxy proxy = plastic(0.1f);
  const Vec3 p1{-1.0f, 0.5f, 0.001f}, p2{-1.004f, 0.507f, 0.003f};  // within one 0.02 step of -1, 0.5, 0
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> U(0, 1);
  int through = 0;
  for (int i = 0; i < 2000; ++i) {
    const DirectionSample s = cache.prepare(p1, n, wo, proxy).sample({U(rng), U(rng)});
    ASSERT_GT(s.pdf, 0.0f);
    ASSERT_EQ(cache.prepare(p2, n, wo, proxy).pdf(s.direction), s.pdf);
    through += room_portals().passes(p1, s.direction);
  }
  EXPECT_GT(through, 1000);  // most light samples leave through a portal from the true point too
  EXPECT_EQ(cache.misses(), 1u);
}

// A point 5 mm from the window's wall rounds onto the wall's plane (x = 2), where no portal is seen:
// it is prepared exactly at itself, and its samples are the exact sampler's.
TEST(ProductCachePortals, KeyThatSeesNoPortalFallsBackToTheExactPoint) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  const Portals portals({quad({2, 0, 1.5f}, {0, 0.8f, 0}, {0, 0, 0.5f})});
  ProductCache cache(table, portals, refined_sampler(), cache_options(4));
  ProductSampler fresh(table, refined_sampler());
  PortalView view(table, portals);
  const Vec3 p{1.995f, 0.3f, 0.4f}, n{0, 0, 1}, wo = normalize(Vec3{-1, 0, 1});
  EXPECT_EQ(cache.round(p, n, wo, plastic(0.2f)).p.x, 2.0f);
  const ProductSampler& s = cache.prepare(p, n, wo, plastic(0.2f));
  ASSERT_TRUE(s.valid());
  EXPECT_EQ(cache.exact_points(), 1u);
  ASSERT_TRUE(view.prepare(p));
  ASSERT_TRUE(fresh.prepare(n, wo, plastic(0.2f), &view));
  for (int k = 0; k < 50; ++k) {
    const Point2 u{(k + 0.5f) / 50, 0.37f};
    EXPECT_EQ(s.sample(u).pdf, fresh.sample(u).pdf);
  }
  // Outside the room (beyond the window) neither the key nor the point sees it: no sample.
  const ProductSampler& out = cache.prepare({2.5f, 0, 1.5f}, {-1, 0, 0}, {-1, 0, 0}, plastic(0.2f));
  EXPECT_FALSE(out.valid());
  EXPECT_EQ(out.pdf({-1, 0, 0}), 0.0f);
}

TEST(ProductCachePortals, CachedSamplerPassesChiSquare) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  ProductCache cache(table, room_portals(), refined_sampler(), cache_options(16));
  const auto points = clustered_points(4, 9);
  int k = 0;
  for (const Point& q : points) {
    cache.prepare(q.p, q.n, q.wo, q.proxy);
    const ProductSampler& s = cache.prepare(q.p, q.n, q.wo, q.proxy);  // a hit
    Chi2Options opt = table_aligned(table.fine_resolution());
    opt.samples = 100000;
    opt.seed = 500 + k++;
    opt.test_count = int(points.size());
    const Chi2Result r = sampler_chi2(s, opt);
    EXPECT_TRUE(r.passed) << r.message;
  }
  EXPECT_GE(cache.hits(), points.size());
}

TEST(ProductCachePortals, RoundingAndOptions) {
  const ImportanceTable table(synthetic_sky(64, 32));
  const Portals portals = room_portals();
  ProductCache cache(table, portals, {}, cache_options(4));
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> U(-3, 3);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p{U(rng), U(rng), U(rng)};
    const Vec3 r = cache.round(p, {0, 0, 1}, {0, 0, 1}, plastic(0.2f)).p;
    EXPECT_LE(std::fabs(r.x - p.x), 0.01f + 1e-6f);
    EXPECT_LE(std::fabs(r.z - p.z), 0.01f + 1e-6f);
  }
  // Beyond 2^20 steps, or not finite: no key, the point itself.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(cache.round({1e5f, 0, 0}, {0, 0, 1}, {0, 0, 1}, plastic(0.2f)).p.x, 1e5f);
  EXPECT_FALSE(cache.prepare({nan, 0, 1}, {0, 0, 1}, {0, 0, 1}, plastic(0.2f)).valid());
  EXPECT_THROW(cache.prepare({0, 0, 1}, {0, 0, 1}, plastic(0.2f)), Error);  // needs the point
  ProductCache plain(table);
  EXPECT_THROW(plain.prepare({0, 0, 1}, {0, 0, 1}, {0, 0, 1}, plastic(0.2f)), Error);
  EXPECT_THROW(ProductCache(table, Portals(), {}, cache_options(4)), Error);
  ProductCacheOptions bad = cache_options(4);
  for (float step : {0.0f, -1.0f, nan, std::numeric_limits<float>::infinity()}) {
    bad.position_step = step;
    EXPECT_THROW(ProductCache(table, portals, {}, bad), Error) << step;
  }
}
