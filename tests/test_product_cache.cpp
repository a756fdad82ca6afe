// SPDX-License-Identifier: Apache-2.0
// ProductCache: the distribution at a shading point is the one prepared for its rounded key, whatever
// the cache held before (so images do not depend on sample order or cache size), the rounding is as
// small as documented, and the sampler it returns is an exact sampler of its own pdf.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "chi2.h"
#include "test_util.h"

using namespace envpis;
using namespace envpis::test;

namespace {

struct Point {
  Vec3 n, wo;
  BsdfProxy proxy;
};

// Shading points in a few tight clusters (the samples of a few pixels), visited in random order.
std::vector<Point> clustered_points(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(-1, 1);
  std::vector<Point> centres;
  for (int c = 0; c < 5; ++c) {
    Point p;
    p.n = random_direction(rng);
    p.wo = random_direction(rng);
    if (dot(p.wo, p.n) < 0) p.wo = -p.wo;
    p.proxy.add_diffuse(0.2f * float(c));
    p.proxy.add_reflection(1.0f, 0.02f + 0.1f * float(c));
    if (c == 4) p.proxy.add_refraction(0.5f, 0.1f, 1.5f);
    centres.push_back(p);
  }
  std::vector<Point> out;
  for (int i = 0; i < count; ++i) {
    Point p = centres[static_cast<std::size_t>(rng() % centres.size())];
    const float jitter = 0.002f;  // about 0.1 degree: the samples of one pixel
    p.n = normalize(p.n + Vec3{U(rng), U(rng), U(rng)} * jitter);
    p.wo = normalize(p.wo + Vec3{U(rng), U(rng), U(rng)} * jitter);
    out.push_back(p);
  }
  return out;
}

}  // namespace

TEST(ProductCache, ReusedSamplerIsTheSamplerOfTheRoundedPoint) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  const ProductSamplerOptions so = refined_sampler();
  ProductCache small(table, so, {128, 1}), large(table, so, {128, 16});
  ProductSampler fresh(table, so);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> U(0, 1);
  for (const Point& p : clustered_points(300, 3)) {
    const ProductSampler& a = small.prepare(p.n, p.wo, p.proxy);
    const ProductSampler& b = large.prepare(p.n, p.wo, p.proxy);
    const ProductCache::Rounded r = small.round(p.n, p.wo, p.proxy);
    ASSERT_TRUE(fresh.prepare(r.n, r.wo, r.proxy));
    for (int k = 0; k < 8; ++k) {
      const Point2 u{U(rng), U(rng)};
      const DirectionSample sf = fresh.sample(u), sa = a.sample(u), sb = b.sample(u);
      ASSERT_EQ(sf.pdf, sa.pdf);
      ASSERT_EQ(sf.pdf, sb.pdf);
      ASSERT_EQ(sf.direction.x, sb.direction.x);
      const Vec3 d = random_direction(rng);
      ASSERT_EQ(fresh.pdf(d), a.pdf(d));
      ASSERT_EQ(fresh.pdf(d), b.pdf(d));
    }
  }
  // Five clusters of ~0.1 degree: the large cache keeps every one, the one-slot cache only the last.
  EXPECT_GT(large.hits(), 150u) << large.misses();
  EXPECT_LT(2 * small.hits(), large.hits()) << small.hits();
}

// The slots are found through a hash index with evictions (backward-shift deletion, CLOCK): with many
// more keys than slots, in an order that revisits some, every prepare() must still return the sampler
// of its own key, a key just used must hit, and hits plus misses count every call.
TEST(ProductCache, HashIndexKeepsEveryKeyFindableThroughEvictions) {
  const ImportanceTable table(synthetic_sky(64, 32), refined_table());
  const ProductSamplerOptions so = refined_sampler();
  for (int entries : {1, 2, 3, 8, 64}) {
    ProductCache cache(table, so, {32, entries});
    ProductSampler fresh(table, so);
    std::mt19937_64 rng(100 + entries);
    std::vector<Point> pool;  // 3 x entries + 5 distinct keys (at K = 32, random directions differ)
    for (const Point& p : clustered_points(3 * entries + 5, 17)) {
      Point q = p;
      q.n = random_direction(rng);
      q.wo = random_direction(rng);
      if (dot(q.wo, q.n) < 0) q.wo = -q.wo;
      pool.push_back(q);
    }
    std::uint64_t calls = 0;
    for (int i = 0; i < 4000; ++i) {
      // Mostly a small working set (hits), sometimes any key of the pool (evictions).
      const std::size_t j = rng() % 4 ? rng() % std::max<std::size_t>(1, entries / 2 + 1) : rng() % pool.size();
      const Point& p = pool[j];
      const ProductSampler& s = cache.prepare(p.n, p.wo, p.proxy);
      ++calls;
      const ProductCache::Rounded r = cache.round(p.n, p.wo, p.proxy);
      ASSERT_TRUE(fresh.prepare(r.n, r.wo, r.proxy));
      const Vec3 d = random_direction(rng);
      ASSERT_EQ(fresh.pdf(d), s.pdf(d)) << "entries " << entries << " call " << i;
      const std::uint64_t hits = cache.hits();
      cache.prepare(p.n, p.wo, p.proxy);  // the same key again: a hit
      ++calls;
      ASSERT_EQ(cache.hits(), hits + 1) << "entries " << entries << " call " << i;
    }
    EXPECT_EQ(cache.hits() + cache.misses(), calls);
    EXPECT_GT(cache.misses(), 100u) << entries;  // the evictions were exercised
  }
}

TEST(ProductCache, RoundingIsAsSmallAsDocumented) {
  const ImportanceTable table(synthetic_sky(64, 32));
  ProductCache cache(table, {}, {128, 16});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> U(0, 1);
  double worst_deg = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 n = random_direction(rng), wo = random_direction(rng);
    BsdfProxy p;
    p.add_diffuse(U(rng));
    p.add_reflection(U(rng) < 0.5f ? 1e-6f : U(rng), U(rng));  // a tiny weight must survive
    p.add_refraction(U(rng), U(rng), 1.0f + 2.0f * U(rng));
    const ProductCache::Rounded r = cache.round(n, wo, p);
    worst_deg = std::max({worst_deg, std::acos(std::min(1.0, double(dot(n, r.n)))) * 180 / kPi,
                          std::acos(std::min(1.0, double(dot(wo, r.wo)))) * 180 / kPi});
    const float sum = p.diffuse + p.reflection + p.refraction;
    const float fraction = p.diffuse / sum;  // rounded to 1/255, or up to 1/255 when smaller
    EXPECT_NEAR(r.proxy.diffuse, std::max(fraction, 1.0f / 255), 0.5f / 255 + 1e-6f);
    EXPECT_GT(r.proxy.reflection, 0.0f);  // a positive weight keeps at least one step
    EXPECT_NEAR(std::sqrt(r.proxy.alpha_reflection), std::sqrt(p.alpha_reflection), 0.5f / 255 + 1e-6f);
    EXPECT_NEAR(std::log2(r.proxy.ior), std::log2(p.ior), 0.5f / 64 + 1e-5f);
  }
  // Components rounded to multiples of 1/128: at most sqrt(3) / 256 radians, 0.39 degree.
  EXPECT_LT(worst_deg, 0.39);
  EXPECT_GT(worst_deg, 0.1);  // and the rounding is real
}

TEST(ProductCache, CachedSamplerPassesChiSquare) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  ProductCache cache(table, refined_sampler());
  const auto points = clustered_points(12, 5);
  int k = 0;
  for (const Point& p : points) {
    cache.prepare(p.n, p.wo, p.proxy);  // warm: the second call below is a hit
    const ProductSampler& s = cache.prepare(p.n, p.wo, p.proxy);
    Chi2Options opt = table_aligned(table.fine_resolution());
    opt.samples = 100000;
    opt.seed = 300 + k++;
    opt.test_count = int(points.size());
    const Chi2Result r = sampler_chi2(s, opt);
    EXPECT_TRUE(r.passed) << r.message;
  }
  EXPECT_GE(cache.hits(), points.size());
}

// A proxy without reflection or refraction is the same for every view on one side of the surface: one
// key serves every wo on that side, and its distribution is the one prepared with the actual wo.
TEST(ProductCache, DiffuseProxiesShareOneKeyPerSide) {
  const ImportanceTable table(synthetic_sky(256, 128), refined_table());
  const ProductSamplerOptions so = refined_sampler();
  ProductCache cache(table, so, {64, 16});
  ProductSampler fresh(table, so);
  std::mt19937_64 rng(23);
  const Vec3 n = normalize(Vec3{0.3f, -0.2f, 0.9f});
  for (const bool translucent : {false, true}) {
    BsdfProxy proxy;
    proxy.add_diffuse(0.8f);
    if (translucent) proxy.add_translucent(0.3f);
    const std::uint64_t misses = cache.misses();
    for (int i = 0; i < 200; ++i) {
      Vec3 wo = random_direction(rng);
      while (std::fabs(dot(n, wo)) < 0.05f) wo = random_direction(rng);  // the rounded n on wo's side too
      const bool below = i % 2 == 1;  // alternate sides: two keys, each prepared once
      if ((dot(n, wo) < 0) != below) wo = -wo;
      const ProductSampler& s = cache.prepare(n, wo, proxy);
      const ProductCache::Rounded r = cache.round(n, wo, proxy);
      ASSERT_TRUE(fresh.prepare(r.n, wo, r.proxy));  // the actual view, at the rounded normal
      for (int c = 0; c < table.cell_count(); ++c)
        ASSERT_NEAR(s.cell_probability(c), fresh.cell_probability(c), 1e-6f + 1e-5f * fresh.cell_probability(c))
            << "point " << i << " cell " << c << (below ? " below" : " above") << (translucent ? ", translucent" : "");
    }
    EXPECT_EQ(cache.misses() - misses, 2u) << (translucent ? "translucent" : "diffuse");
  }
  // A glossy lobe makes the key depend on the view again.
  BsdfProxy glossy;
  glossy.add_diffuse(0.5f);
  glossy.add_reflection(0.5f, 0.2f);
  const std::uint64_t misses = cache.misses();
  cache.prepare(n, normalize(Vec3{0, 0, 1}), glossy);
  cache.prepare(n, normalize(Vec3{0.5f, 0, 1}), glossy);
  EXPECT_EQ(cache.misses() - misses, 2u);
}

TEST(ProductCache, InvalidPointsAndProxies) {
  const ImportanceTable table(synthetic_sky(64, 32));
  ProductCache cache(table);
  BsdfProxy p;
  p.add_reflection(1, 0.1f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Vec3 bad : {Vec3{0, 0, 0}, Vec3{nan, 0, 1}}) {
    const ProductSampler& s = cache.prepare(bad, {0, 0, 1}, p);
    EXPECT_FALSE(s.valid());
    EXPECT_EQ(s.sample({0.3f, 0.6f}).pdf, 0.0f);
    EXPECT_EQ(s.pdf({0, 0, 1}), 0.0f);
    EXPECT_FALSE(cache.prepare({0, 0, 1}, bad, p).valid());
  }
  // A proxy with a NaN weight: the weight counts as 0; an all-zero proxy falls back to the environment.
  BsdfProxy odd;
  odd.reflection = nan;
  odd.diffuse = 1;
  const ProductSampler& s = cache.prepare({0, 0, 1}, {0, 0, 1}, odd);
  EXPECT_TRUE(s.valid());
  EXPECT_EQ(cache.round({0, 0, 1}, {0, 0, 1}, odd).proxy.reflection, 0.0f);
  const ProductSampler& z = cache.prepare({0, 0, 1}, {0, 0, 1}, BsdfProxy{});
  EXPECT_TRUE(z.valid());
  EXPECT_TRUE(z.uses_environment_fallback());
}

TEST(ProductCache, RejectsBadOptions) {
  const ImportanceTable table(synthetic_sky(64, 32));
  EXPECT_THROW(ProductCache(table, {}, {0, 4}), Error);
  EXPECT_THROW(ProductCache(table, {}, {4096, 4}), Error);
  EXPECT_THROW(ProductCache(table, {}, {128, 0}), Error);
  EXPECT_THROW(ProductCache(table, {}, {128, 1025}), Error);
}
