// SPDX-License-Identifier: Apache-2.0
// The statistical sweep (label `sweep`, not in the default run): chi-square goodness of fit of the
// product sampler over 1000 random (map, top resolution, proxy, normal, outgoing direction, mixture)
// configurations, with a Sidak correction for the family, plus a check that the 1000 p-values are
// uniform (as they must be when every pdf matches its sampler). Run: ctest --test-dir build -L sweep
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "chi2.h"
#include "test_util.h"

using namespace envpis;
using namespace envpis::test;

TEST(Sweep, ProductSamplerChiSquareOver1000Configurations) {
  std::vector<std::pair<std::string, EnvironmentMap>> maps;
  maps.emplace_back("synthetic-sky", synthetic_sky(256, 128));
  maps.emplace_back("synthetic-equal-area", synthetic_latlong(96, 96, [](int x, int y) { return 0.05f + float((x * y) % 17); }));
  if (have_blender_maps())
    for (const auto& n : blender_map_names()) maps.emplace_back(n, EnvironmentMap::load(blender_map(n)));
  const int tops[] = {8, 12, 16};
  std::vector<std::vector<std::shared_ptr<ImportanceTable>>> tables(maps.size());
  for (std::size_t m = 0; m < maps.size(); ++m)
    for (int T : tops) {
      ImportanceTableOptions o;
      o.top_resolution = T;
      o.fine_resolution = 384;  // keeps the sweep fast; the default resolution is tested elsewhere
      tables[m].push_back(std::make_shared<ImportanceTable>(maps[m].second, o));
    }
  const int count = 1000;
  std::mt19937_64 rng(2018);
  std::uniform_real_distribution<float> U(0, 1);
  std::vector<double> pvalues;
  int passed = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t m = rng() % maps.size();
    const auto& table = *tables[m][rng() % 3];
    ProductSamplerOptions opt;
    opt.env_mix = U(rng) < 0.3f ? 0.1f : 0.0f;
    opt.proxy.transform = static_cast<RoughnessTransform>(rng() % 3);
    opt.proxy.min_alpha = U(rng) < 0.5f ? 0.35f : 0.0f;
    if (U(rng) < 0.3f) opt.proxy.reflection_lobe = ReflectionLobe::HalfVector;
    ProductSampler ps(table, opt);
    BsdfProxy proxy;
    if (U(rng) < 0.6f) proxy.add_diffuse(U(rng));
    if (U(rng) < 0.3f) proxy.add_translucent(U(rng));
    if (U(rng) < 0.8f) proxy.add_reflection(U(rng), U(rng) * U(rng));
    if (U(rng) < 0.4f) proxy.add_refraction(U(rng), U(rng) * U(rng), 0.5f + 1.5f * U(rng));
    const Vec3 n = random_direction(rng), wo = random_direction(rng);
    ASSERT_TRUE(ps.prepare(n, wo, proxy));
    Chi2Options c;
    c.bins = 48;
    c.sub = 8;
    c.samples = 40000;
    c.seed = 5000 + k;
    c.test_count = count;
    const auto r = sampler_chi2(ps, c);
    pvalues.push_back(r.p_value);
    passed += r.passed;
    EXPECT_TRUE(r.passed) << maps[m].first << " config " << k << ": " << r.message;
  }
  // Kolmogorov-Smirnov distance of the p-values from uniform.
  std::sort(pvalues.begin(), pvalues.end());
  double ks = 0;
  for (int i = 0; i < count; ++i)
    ks = std::max({ks, std::abs(pvalues[i] - double(i) / count), std::abs(pvalues[i] - double(i + 1) / count)});
  const int below_1pct = int(std::count_if(pvalues.begin(), pvalues.end(), [](double p) { return p < 0.01; }));
  std::printf("sweep: %d / %d configurations pass at family-wise alpha 0.01 (Sidak) = %.1f%%; %d p-values < 0.01; "
              "KS distance of p-values from uniform %.4f (5%% critical value %.4f)\n",
              passed, count, 100.0 * passed / count, below_1pct, ks, 1.36 / std::sqrt(double(count)));
  // p-values of a pdf that matches its sampler are (nearly) uniform. The chi-square statistic's
  // distribution is only asymptotically chi-square, so allow twice the 5% critical distance.
  EXPECT_LT(ks, 2 * 1.36 / std::sqrt(double(count)));
}
