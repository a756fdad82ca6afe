// SPDX-License-Identifier: Apache-2.0
// DiscreteDistribution2D (the top levels), CumulativeDistribution2DView (the fine level) and the two-level path of ImportanceTable: probabilities,
// sampling frequencies (chi-square), and sample -> invert round trips.
#include <gtest/gtest.h>

#include <boost/math/distributions/chi_squared.hpp>

#include <random>
#include <vector>

#include "envpis/envpis.h"
#include "test_util.h"

using namespace envpis;

namespace {
std::vector<float> random_masses(std::mt19937& rng, int w, int h) {
  std::uniform_real_distribution<float> U(0, 1);
  std::vector<float> m(static_cast<std::size_t>(w) * h);
  for (float& v : m) v = U(rng) < 0.2f ? 0.0f : U(rng);
  return m;
}

// invert(sample(u)) == u for 100000 random u.
template <class Distribution>
void expect_invert_undoes_sample(const Distribution& d, std::mt19937& rng) {
  std::uniform_real_distribution<float> U(0, 1);
  for (int k = 0; k < 100000; ++k) {
    const Point2 u{U(rng), U(rng)};
    const auto s = d.sample(u);
    const Point2 v = d.invert(s.x, s.y, s.offset);
    ASSERT_NEAR(v.x, u.x, 2e-5f) << k;
    ASSERT_NEAR(v.y, u.y, 2e-5f) << k;
  }
}
}  // namespace

// pmf against sums in double, for the 12-wide fast path and the general loop.
TEST(DiscreteDistribution2D, PmfMatchesDoubleSums) {
  std::mt19937 rng(41);
  for (int w : {1, 3, 4, 11, 12, 13, 16}) {
    const int h = w + 1;
    const std::vector<float> m = random_masses(rng, w, h);
    const DiscreteDistribution2D d(m.data(), w, h);
    double total = 0;
    for (float v : m) total += v;
    ASSERT_NEAR(d.total(), total, 1e-6 * total) << "w=" << w;
    for (int i = 0; i < w * h; ++i) ASSERT_NEAR(d.pmf(i), m[i] / total, 1e-6) << "w=" << w << " cell " << i;
    EXPECT_EQ(d.padded_size() % 16, 0);
    EXPECT_GE(d.padded_size(), w * h);
  }
}

// Sampling frequencies against the pmf (chi-square, fixed seed); cells of mass 0 are never chosen.
TEST(DiscreteDistribution2D, SamplesFollowThePmf) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> U(0, 1);
  for (int w : {5, 12}) {
    const int h = 7;
    const std::vector<float> m = random_masses(rng, w, h);
    const DiscreteDistribution2D d(m.data(), w, h);
    const int n = 200000;
    std::vector<int> count(m.size(), 0);
    for (int k = 0; k < n; ++k) {
      const auto s = d.sample({U(rng), U(rng)});
      ASSERT_GT(m[static_cast<std::size_t>(s.y) * w + s.x], 0.0f);
      ASSERT_FLOAT_EQ(s.pmf, d.pmf(s.x, s.y));
      ++count[static_cast<std::size_t>(s.y) * w + s.x];
    }
    double chi2 = 0;
    int dof = -1;
    for (std::size_t i = 0; i < m.size(); ++i) {
      const double e = n * double(d.pmf(static_cast<int>(i)));
      if (e == 0) continue;
      chi2 += (count[i] - e) * (count[i] - e) / e;
      ++dof;
    }
    const double p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), chi2));
    EXPECT_GT(p, 0.005) << "w=" << w << " chi2=" << chi2 << " dof=" << dof;
  }
}

// invert(sample(u)) == u, and the offsets come back too.
TEST(DiscreteDistribution2D, InvertUndoesSample) {
  std::mt19937 rng(3);
  const std::vector<float> m = random_masses(rng, 12, 12);
  expect_invert_undoes_sample(DiscreteDistribution2D(m.data(), 12, 12), rng);
}

TEST(DiscreteDistribution2D, EmptyAndInvalid) {
  DiscreteDistribution2D zero(4, 4);
  EXPECT_FALSE(zero.valid());
  EXPECT_EQ(zero.update(), 0.0f);
  EXPECT_FALSE(zero.valid());
  EXPECT_EQ(zero.pmf(3), 0.0f);
  const float denormal[] = {1e-40f, 0, 0, 0};
  EXPECT_FALSE(DiscreteDistribution2D(denormal, 2, 2).valid());
  EXPECT_THROW(DiscreteDistribution2D(0, 3), Error);
}

namespace {
// An n x n CumulativeDistribution2DView with its own storage.
struct Cumulative {
  std::vector<float> mass, cdf;
  float total;
  Cumulative(std::vector<float> m, int n) : mass(std::move(m)), cdf(mass.size()) {
    total = static_cast<float>(CumulativeDistribution2DView::build(mass.data(), n, cdf.data()));
  }
  CumulativeDistribution2DView view(int n) const { return {mass.data(), cdf.data(), total, n}; }
};
}  // namespace

// Sampling frequencies against the pmf (chi-square, fixed seed), the pmf against sums in double, and
// cells of mass 0 never chosen, for 1 x 1 up to the fine level's typical size.
TEST(CumulativeDistribution2DView, SamplesFollowThePmf) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> U(0, 1);
  for (int n : {1, 2, 7, 30}) {
    const Cumulative c(random_masses(rng, n, n), n);
    const CumulativeDistribution2DView d = c.view(n);
    double total = 0;
    for (float v : c.mass) total += v;
    for (int i = 0; i < n * n; ++i) ASSERT_NEAR(d.pmf(i % n, i / n), c.mass[i] / total, 1e-6) << n;
    const int draws = 300000;
    std::vector<int> count(c.mass.size(), 0);
    for (int k = 0; k < draws; ++k) {
      const auto s = d.sample({U(rng), U(rng)});
      ASSERT_GT(c.mass[static_cast<std::size_t>(s.y) * n + s.x], 0.0f) << n;
      ASSERT_FLOAT_EQ(s.pmf, d.pmf(s.x, s.y));
      ++count[static_cast<std::size_t>(s.y) * n + s.x];
    }
    double chi2 = 0;
    int dof = -1;
    for (std::size_t i = 0; i < c.mass.size(); ++i) {
      const double e = draws * double(d.pmf(static_cast<int>(i % n), static_cast<int>(i / n)));
      if (e == 0) continue;
      chi2 += (count[i] - e) * (count[i] - e) / e;
      ++dof;
    }
    if (dof < 1) continue;  // one cell with mass: nothing to test beyond the asserts above
    const double p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), chi2));
    EXPECT_GT(p, 0.005) << "n=" << n << " chi2=" << chi2 << " dof=" << dof;
  }
}

// invert(sample(u)) == u, offsets included; a zero distribution has pmf 0 but still samples inside.
TEST(CumulativeDistribution2DView, InvertUndoesSampleAndZeroIsHarmless) {
  std::mt19937 rng(23);
  const int n = 30;
  const Cumulative c(random_masses(rng, n, n), n);
  expect_invert_undoes_sample(c.view(n), rng);
  const Cumulative zero(std::vector<float>(16, 0.0f), 4);
  EXPECT_EQ(zero.total, 0.0f);
  const auto s = zero.view(4).sample({0.99f, 0.3f});
  EXPECT_EQ(s.pmf, 0.0f);
  EXPECT_TRUE(s.x >= 0 && s.x < 4 && s.y >= 0 && s.y < 4);
}

// The two-level path: invert(direction of sample(u)) == u through the fine level and the mapping, for
// the environment's own top level and a product sampler's, so stratified u stay stratified directions.
TEST(DiscreteDistribution2D, TwoLevelSampleThenInvertRoundTrips) {
  const auto map = test::synthetic_sky(256, 128);
  const ImportanceTable t(map);
  ProductSampler ps(t);
  BsdfProxy proxy;
  proxy.add_reflection(1.0f, 0.2f);
  ASSERT_TRUE(ps.prepare(normalize({0.3f, 0.2f, 1}), normalize({1, 0, 1}), proxy));
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0, 1);
  for (const DiscreteDistribution2D* top : {&t.top_level(), &ps.top_level()}) {
    int far = 0;
    const int n = 20000;
    for (int k = 0; k < n; ++k) {
      const Point2 u{U(rng), U(rng)};
      const DirectionSample s = t.sample(*top, u);
      ASSERT_GT(s.pdf, 0);
      const Point2 v = t.invert(*top, s.direction);
      // Round-off of the mapping moves a point by a few 1e-6 of the square; the inverse stretches
      // that by the local density ratio. Allow a few outliers where a texel is very light.
      if (std::fabs(v.x - u.x) > 1e-3f || std::fabs(v.y - u.y) > 1e-3f) ++far;
    }
    EXPECT_LT(far, n / 1000) << "samples whose inverse is not their u";
  }
}
