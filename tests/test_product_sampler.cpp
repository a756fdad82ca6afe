// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <new>
#include <random>

#include "chi2.h"
#include "envpis/equal_area.h"
#include "kernels.h"
#include "proxy_internal.h"
#include "test_util.h"

// Counts heap allocations, to check that prepare() and sample() never allocate.
static std::atomic<long> g_allocations{0};
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace envpis;
using namespace envpis::test;

namespace {

struct Config {
  Vec3 n, wo;
  BsdfProxy proxy;
  std::string label;
};

/// Random shading configurations: normal anywhere, wo in its upper hemisphere (some grazing, some
/// from below for refraction), proxies mixing the four lobes with roughness from 0 to 1.
std::vector<Config> random_configs(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(0, 1);
  std::vector<Config> out;
  for (int i = 0; i < count; ++i) {
    Config c;
    c.n = random_direction(rng);
    Vec3 wo = random_direction(rng);
    if (dot(wo, c.n) < 0 && i % 5 != 0) wo = -wo;  // every fifth: seen from below
    if (i % 7 == 3) wo = normalize(wo - c.n * (dot(wo, c.n) * 0.98f));  // near grazing
    c.wo = wo;
    const int kind = i % 6;
    const float a = std::vector<float>{0.0f, 0.02f, 0.1f, 0.2f, 0.3f, 0.5f, 1.0f}[i % 7];
    switch (kind) {
      case 0: c.proxy.add_reflection(1, a); break;
      case 1: c.proxy.add_diffuse(0.7f); c.proxy.add_reflection(0.3f, a); break;
      case 2: c.proxy.add_reflection(0.1f, a); c.proxy.add_refraction(0.9f, a, 1.5f); break;
      case 3: c.proxy.add_diffuse(0.5f); c.proxy.add_translucent(0.5f); break;
      case 4: c.proxy.add_refraction(1, a, i % 2 ? 1.0f : 0.7f); break;
      default: c.proxy.add_diffuse(U(rng)); c.proxy.add_reflection(U(rng), a); c.proxy.add_refraction(U(rng), U(rng), 1.33f); break;
    }
    c.label = "config " + std::to_string(i) + " kind " + std::to_string(kind) + " alpha " + std::to_string(a);
    out.push_back(c);
  }
  return out;
}

Chi2Result product_chi2(const ProductSampler& ps, std::uint64_t seed, int tests, std::size_t samples = 100000) {
  Chi2Options opt = table_aligned(ps.table().fine_resolution());
  opt.samples = samples;
  opt.seed = seed;
  opt.test_count = tests;
  return sampler_chi2(ps, opt);
}

std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> test_tables() {
  std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> t;
  t.emplace_back("synthetic sky", std::make_shared<ImportanceTable>(synthetic_sky(256, 128)));
  EnvironmentMapOptions o;
  o.rotation = Mat3::rotate_z(-50);
  t.emplace_back("synthetic equal-area",
                 std::make_shared<ImportanceTable>(synthetic_latlong(120, 120, [](int x, int y) {
                   return 0.1f + ((x / 10 + y / 10) % 3 == 0 ? 30.0f : 0.0f);
                 }, o)));
  if (have_blender_maps())
    for (const char* name : {"sunset", "studio", "forest"})
      t.emplace_back(name, std::make_shared<ImportanceTable>(EnvironmentMap::load(blender_map(name))));
  return t;
}

// The weights kernel's return value is the total of the weights it wrote (ProductSampler floors with it),
// up to the round-off of a different summation order.
void expect_returned_total(float returned, const std::vector<float>& weights, const char* kernel) {
  double total = 0;
  for (float w : weights) total += w;
  EXPECT_NEAR(returned, total, 1e-5 * total) << kernel;
}

}  // namespace

TEST(ProductSampler, ChiSquareOverManyConfigurations) {
  const auto tables = test_tables();
  const int per_table = 14;  // 5 tables x 14 = 70 configurations (40 without blender-data)
  const int tests = per_table * int(tables.size());
  int failures = 0, k = 0;
  for (const auto& [name, table] : tables) {
    ProductSampler ps(*table);
    for (const Config& c : random_configs(per_table, 100 + k)) {
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy)) << name << " " << c.label;
      const auto r = product_chi2(ps, 1000 + k++, tests);
      if (!r.passed) ++failures;
      EXPECT_TRUE(r.passed) << name << " " << c.label << ": " << r.message;
    }
  }
  std::printf("%d product chi-square tests, %d failed\n", k, failures);
  EXPECT_GE(k, 50);
}

TEST(ProductSampler, SamplePdfEqualsPdfOfDirectionAndIntegratesToOne) {
  const auto tables = test_tables();
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<float> U(0, 1);
  int k = 0;
  for (const auto& [name, table] : tables) {
    ProductSampler ps(*table);
    for (const Config& c : random_configs(4, 7 + k++)) {
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy));
      for (int i = 0; i < 5000; ++i) {
        const DirectionSample s = ps.sample({U(rng), U(rng)});
        ASSERT_GT(s.pdf, 0.0f);
        ASSERT_TRUE(std::isfinite(s.pdf));
        ASSERT_NEAR(length(s.direction), 1.0f, 1e-5f);
        ASSERT_NEAR(s.pdf, ps.pdf(s.direction), 1e-4f * s.pdf);
        ASSERT_EQ(s.cell, table->cell_of_direction(s.direction));
      }
      // Integral by importance sampling from a differently configured product sampler (wider lobes,
      // half environment) mixed with uniform directions: the ratio pdf / q stays bounded.
      ProductSamplerOptions wide;
      wide.env_mix = 0.5f;
      wide.proxy.min_alpha = 0.5f;
      ProductSampler helper(*table, wide);
      ASSERT_TRUE(helper.prepare(c.n, c.wo, c.proxy));
      double acc = 0;
      const int n = 200000;
      for (int i = 0; i < n; ++i) {
        const Vec3 d = U(rng) < 0.7f ? helper.sample({U(rng), U(rng)}).direction : random_direction(rng);
        acc += ps.pdf(d) / (0.7 * helper.pdf(d) + 0.3 / (4 * M_PI));
      }
      EXPECT_NEAR(acc / n, 1.0, 0.01) << name << " " << c.label;
    }
  }
}

TEST(ProductSampler, SimdWeightsEqualScalarReference) {
  const auto tables = test_tables();
  for (const auto& [name, table] : tables) {
    ProductSamplerOptions simd_opt, scalar_opt;  // the paper's top level: the kernels' weights as they are
    simd_opt.cell_estimate = scalar_opt.cell_estimate = CellEstimate::Cone;  // the reference below
    simd_opt.env_floor = scalar_opt.env_floor = 0;
    scalar_opt.simd = Simd::Scalar;
    ProductSampler simd(*table, simd_opt), scalar(*table, scalar_opt);
    for (const Config& c : random_configs(40, 3)) {
      ASSERT_TRUE(simd.prepare(c.n, c.wo, c.proxy));
      ASSERT_TRUE(scalar.prepare(c.n, c.wo, c.proxy));
      // An independent reference: E[c] * proxy evaluated at each cone, normalized.
      const PreparedProxy& pp = simd.prepared_proxy();
      std::vector<double> ref(table->cell_count());
      double sum = 0;
      for (int i = 0; i < table->cell_count(); ++i) {
        const Cone& cone = table->cell_cone(i);
        sum += ref[i] = double(table->cell_probability(i)) * pp.eval_cone(cone.axis, cone.cos_half_angle, cone.sin_half_angle);
      }
      for (int i = 0; i < table->cell_count(); ++i) {
        const double r = ref[i] / sum;
        // The SIMD kernels use the hardware's square root and reciprocal estimates (relative error
        // < 3.7e-4 each, src/simd_ops.h); the scalar kernel is exact.
        ASSERT_NEAR(simd.cell_probability(i), scalar.cell_probability(i), 2e-3 * std::max(1e-3, r)) << name << " " << c.label << " cell " << i;
        ASSERT_NEAR(scalar.cell_probability(i), r, 1e-4 * std::max(1e-3, r)) << name << " " << c.label << " cell " << i;
      }
    }
  }
}

// ProductSampler runs one kernel set (options.simd, the widest by default); this runs every set this
// build has and this CPU can run (scalar, SSE2, AVX2, AVX-512) on the product weights and both
// mappings, against the scalar kernels, over the cell arrays of real tables and the random proxies.
TEST(ProductSampler, EveryAvailableKernelSetMatchesTheScalarKernels) {
  const std::vector<const detail::Kernels*> sets = detail::kernels_available();
  ASSERT_GE(sets.size(), 2u);
  const detail::Kernels& ref = detail::kernels_scalar();
  std::string names;
  for (const detail::Kernels* k : sets) names += std::string(" ") + k->name;
  std::printf("kernel sets on this CPU:%s; ProductSampler uses %s\n", names.c_str(), to_string(simd_resolve(Simd::Best)));
  for (const auto& [name, table] : test_tables()) {
    const detail::CellArrays cells = detail::cell_arrays(*table);
    std::vector<float> expected(cells.padded_count), got(cells.padded_count);
    for (const Config& c : random_configs(30, 17)) {
      const PreparedProxy pp = prepare_proxy(c.proxy, c.n, c.wo);
      ASSERT_TRUE(pp.valid());
      const detail::LobeParams lobes = detail::to_lobe_params(pp);
      ref.product_weights(cells, lobes, expected.data());
      double total = 0;
      for (float w : expected) total += w;
      for (const detail::Kernels* k : sets) {
        const float returned = k->product_weights(cells, lobes, got.data());
        expect_returned_total(returned, got, k->name);
        for (int i = 0; i < cells.padded_count; ++i) {
          // Hardware estimates of 1/sqrt and 1/x (relative error < 3.7e-4 each, src/simd_ops.h).
          ASSERT_NEAR(got[i], expected[i], 2e-3 * std::max(double(expected[i]), 1e-6 * total))
              << k->name << " " << name << " " << c.label << " cell " << i;
        }
      }
    }
  }
  // Mappings, with lengths that leave tails for every lane count.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> U(0, 1);
  for (const std::size_t n : {std::size_t(1), std::size_t(7), std::size_t(33), std::size_t(1000)}) {
    std::vector<float> u(n), v(n), x(n), y(n), z(n), ex(n), ey(n), ez(n), bu(n), bv(n), eu(n), ev(n);
    for (std::size_t i = 0; i < n; ++i) {
      u[i] = i < 4 ? float(i % 2) : U(rng);
      v[i] = i < 4 ? float(i / 2) : U(rng);
    }
    ref.square_to_sphere(n, u.data(), v.data(), ex.data(), ey.data(), ez.data());
    ref.sphere_to_square(n, ex.data(), ey.data(), ez.data(), eu.data(), ev.data());
    for (const detail::Kernels* k : sets) {
      k->square_to_sphere(n, u.data(), v.data(), x.data(), y.data(), z.data());
      k->sphere_to_square(n, ex.data(), ey.data(), ez.data(), bu.data(), bv.data());
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(x[i], ex[i], 1e-6f) << k->name << " n=" << n << " i=" << i;
        ASSERT_NEAR(y[i], ey[i], 1e-6f) << k->name << " n=" << n << " i=" << i;
        ASSERT_NEAR(z[i], ez[i], 1e-6f) << k->name << " n=" << n << " i=" << i;
        ASSERT_NEAR(bu[i], eu[i], 1e-6f) << k->name << " n=" << n << " i=" << i;
        ASSERT_NEAR(bv[i], ev[i], 1e-6f) << k->name << " n=" << n << " i=" << i;
      }
    }
  }
}

TEST(ProductSampler, ConeEstimateIsConservative) {
  // The closest-direction estimate of every cell bounds the proxy at every direction of that cell.
  const ImportanceTable table(synthetic_sky(128, 64));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> U(0, 1);
  for (const Config& c : random_configs(30, 11)) {
    const PreparedProxy pp = prepare_proxy(c.proxy, c.n, c.wo);
    ASSERT_TRUE(pp.valid());
    for (int cell = 0; cell < table.cell_count(); ++cell) {
      const Cone& cone = table.cell_cone(cell);
      const float bound = pp.eval_cone(cone.axis, cone.cos_half_angle, cone.sin_half_angle);
      const int T = table.top_resolution();
      for (int i = 0; i < 40; ++i) {
        const Vec3 d = equal_area_square_to_sphere({(cell % T + U(rng)) / T, (cell / T + U(rng)) / T});
        ASSERT_LE(pp.eval(d), bound * (1 + 1e-4f) + 1e-7f) << c.label << " cell " << cell;
      }
    }
  }
}

TEST(ProductSampler, UnbiasedAgainstQuadrature) {
  // Estimate I = integral of L(w) g(w) with g a glossy lobe max(0, R.w)^k (the "BSDF") by the
  // product sampler alone and by environment sampling alone; both must agree with a fine quadrature
  // (z-test, 4 sigma). g vanishes exactly where the proxy's reflection lobe does, so the product
  // estimator alone is unbiased.
  const EnvironmentMap map = have_blender_maps() ? EnvironmentMap::load(blender_map("studio")) : synthetic_sky();
  const ImportanceTable table(map);
  ProductSampler ps(table);
  const Vec3 n = normalize(Vec3{0.3f, -0.2f, 1.0f}), wo = normalize(Vec3{-0.5f, 0.4f, 0.8f});
  const Vec3 r = normalize(n * (2 * dot(n, wo)) - wo);
  const float k = 40;
  auto g = [&](Vec3 w) { return dot(w, n) > 0 ? std::pow(std::max(0.0f, dot(r, w)), k) : 0.0f; };
  BsdfProxy proxy;
  proxy.add_reflection(1.0f, 0.15f);
  ASSERT_TRUE(ps.prepare(n, wo, proxy));
  // Quadrature on a fine equal-area grid (each point has solid angle 4 pi / m^2).
  const int m = 3000;
  double quad = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const Vec3 w = equal_area_square_to_sphere({(i + 0.5f) / m, (j + 0.5f) / m});
      const float gw = g(w);
      if (gw > 0) quad += map.eval(w).average() * gw;
    }
  quad *= 4 * M_PI / (double(m) * m);
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<float> U(0, 1);
  auto estimate = [&](auto&& sampler) {
    double s = 0, s2 = 0;
    const int count = 400000;
    for (int i = 0; i < count; ++i) {
      const DirectionSample ds = sampler({U(rng), U(rng)});
      const double f = ds.pdf > 0 ? map.eval(ds.direction).average() * g(ds.direction) / ds.pdf : 0.0;
      s += f;
      s2 += f * f;
    }
    const double mean = s / count, var = (s2 / count - mean * mean) / count;
    return std::pair{mean, std::sqrt(var)};
  };
  const auto [prod, prod_se] = estimate([&](Point2 u) { return ps.sample(u); });
  const auto [env, env_se] = estimate([&](Point2 u) { return table.sample(u); });
  // The quadrature has its own small error; allow 0.3% of it besides the statistical error.
  EXPECT_LT(std::abs(prod - quad), 4 * prod_se + 3e-3 * quad) << prod << " vs " << quad;
  EXPECT_LT(std::abs(env - quad), 4 * env_se + 3e-3 * quad) << env << " vs " << quad;
  std::printf("quadrature %.6g  product %.6g +- %.2g  env %.6g +- %.2g  (variance ratio env/product %.2f)\n", quad, prod,
              prod_se, env, env_se, (env_se * env_se) / (prod_se * prod_se));
  EXPECT_LT(prod_se, env_se);  // product sampling must help on a glossy lobe
}

// prepare(), sample() and pdf() over 20 shading points allocate nothing (and produce samples).
static void expect_no_allocation(ProductSampler& ps) {
  const auto configs = random_configs(20, 9);
  const long before = g_allocations.load();
  float acc = 0;
  for (const Config& c : configs) {
    ps.prepare(c.n, c.wo, c.proxy);
    for (int i = 0; i < 10; ++i) {
      const DirectionSample s = ps.sample({i / 10.0f, 0.37f});
      acc += s.pdf + ps.pdf(s.direction);
    }
  }
  EXPECT_EQ(g_allocations.load(), before);
  EXPECT_GT(acc, 0);
}

TEST(ProductSampler, PrepareAndSampleDoNotAllocate) {
  const ImportanceTable table(synthetic_sky());
  ProductSampler ps(table);
  expect_no_allocation(ps);
}

// A shading point the proxy gives nothing (all-NaN weights) right after a valid one falls back to the
// environment: the fallback must not see the previous point's distribution (the Python tests found
// a sampler that kept it and returned pdf 0).
TEST(ProductSampler, NanProxyAfterAValidPointFallsBackToTheEnvironment) {
  const ImportanceTable table(test::synthetic_sky(128, 64));
  ProductSampler ps(table);
  BsdfProxy good;
  good.add_reflection(1.0f, 0.2f);
  ASSERT_TRUE(ps.prepare({0, 0, 1}, normalize({1, 0, 1}), good));
  ASSERT_FALSE(ps.uses_environment_fallback());
  const float nan = std::nanf("");
  BsdfProxy bad;
  bad.diffuse = bad.translucent = bad.reflection = bad.refraction = nan;
  bad.alpha_reflection = bad.alpha_refraction = bad.ior = nan;
  ASSERT_TRUE(ps.prepare({0, 0, 1}, normalize({1, 0, 1}), bad));
  EXPECT_TRUE(ps.uses_environment_fallback());
  for (const Point2 u : {Point2{0.2f, 0.7f}, Point2{0.5f, 0.5f}, Point2{0.9f, 0.1f}}) {
    const DirectionSample s = ps.sample(u);
    ASSERT_GT(s.pdf, 0.0f);
    EXPECT_NEAR(s.pdf, table.pdf(s.direction), 1e-5f * s.pdf);
  }
}

TEST(ProductSampler, DegenerateShadingPoints) {
  const ImportanceTable table(synthetic_sky());
  ProductSampler ps(table);
  BsdfProxy glossy;
  glossy.add_reflection(1, 0.2f);
  const float nan = std::nanf("");
  // Zero or NaN normal / wo: invalid, no sample, pdf 0, never NaN.
  for (auto [n, wo] : {std::pair{Vec3{0, 0, 0}, Vec3{0, 0, 1}}, std::pair{Vec3{0, 0, 1}, Vec3{0, 0, 0}},
                       std::pair{Vec3{nan, 0, 1}, Vec3{0, 0, 1}}, std::pair{Vec3{0, 0, 1}, Vec3{0, nan, 1}},
                       std::pair{Vec3{0, 0, INFINITY}, Vec3{0, 0, 1}}}) {
    EXPECT_FALSE(ps.prepare(n, wo, glossy));
    EXPECT_EQ(ps.sample({0.5f, 0.5f}).pdf, 0.0f);
    EXPECT_EQ(ps.pdf({0, 0, 1}), 0.0f);
  }
  // An all-zero proxy falls back to the environment distribution.
  ASSERT_TRUE(ps.prepare({0, 0, 1}, {0, 0, 1}, BsdfProxy{}));
  EXPECT_TRUE(ps.uses_environment_fallback());
  EXPECT_NEAR(ps.pdf({0.3f, 0.1f, 0.9f}), table.pdf(normalize(Vec3{0.3f, 0.1f, 0.9f})), 1e-6f);
  // wo below the surface, roughness 0 and 1, IOR 1 and below 1, NaN IOR: valid, finite, consistent.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> U(0, 1);
  for (float a : {0.0f, 1.0f})
    for (float ior : {1.0f, 0.6f, 1.5f, nan, -2.0f, 0.0f})
      for (Vec3 wo : {Vec3{0.3f, 0, 1}, Vec3{0.3f, 0, -1}, Vec3{1, 0, 0}}) {
        BsdfProxy p;
        p.add_reflection(0.5f, a);
        p.add_refraction(0.5f, a, ior);
        ASSERT_TRUE(ps.prepare({0, 0, 1}, wo, p)) << a << " " << ior;
        for (int i = 0; i < 200; ++i) {
          const DirectionSample s = ps.sample({U(rng), U(rng)});
          ASSERT_TRUE(s.pdf > 0 && std::isfinite(s.pdf)) << a << " " << ior;
          ASSERT_TRUE(std::isfinite(s.direction.x) && std::isfinite(s.direction.y) && std::isfinite(s.direction.z));
          ASSERT_NEAR(s.pdf, ps.pdf(s.direction), 1e-4f * s.pdf);
        }
      }
  // Empty table (all-black map): invalid.
  const ImportanceTable black(synthetic_latlong(16, 8, [](int, int) { return 0.0f; }));
  ProductSampler pb(black);
  EXPECT_FALSE(pb.prepare({0, 0, 1}, {0, 0, 1}, glossy));
  EXPECT_EQ(pb.sample({0.2f, 0.2f}).pdf, 0.0f);
}

TEST(ProductSampler, EnvironmentMixtureAndOptions) {
  const ImportanceTable table(synthetic_sky());
  ProductSamplerOptions o;
  o.env_mix = 0.25f;
  ProductSampler mixed(table, o), plain(table);
  BsdfProxy p;
  p.add_reflection(1, 0.1f);
  const Vec3 n{0, 0, 1}, wo = normalize(Vec3{1, 0, 1});
  ASSERT_TRUE(mixed.prepare(n, wo, p));
  ASSERT_TRUE(plain.prepare(n, wo, p));
  for (int c = 0; c < table.cell_count(); ++c)
    EXPECT_NEAR(mixed.cell_probability(c), 0.75f * plain.cell_probability(c) + 0.25f * table.cell_probability(c), 1e-6f);
  const auto r = product_chi2(mixed, 5, 1);
  EXPECT_TRUE(r.passed) << r.message;
  o.env_mix = 1.5f;
  EXPECT_THROW(ProductSampler(table, o), Error);
}

namespace {
// The smallest ratio of the product's density to the environment table's, over 400 random directions
// at each configuration, where both sample (pdf > 0).
double worst_density_ratio(ProductSampler& ps, const ImportanceTable& table, const std::vector<Config>& configs,
                           unsigned seed) {
  std::mt19937_64 rng(seed);
  double worst = HUGE_VAL;
  for (const Config& c : configs) {
    if (!ps.prepare(c.n, c.wo, c.proxy)) continue;
    for (int i = 0; i < 400; ++i) {
      const Vec3 d = random_direction(rng);
      const float p = ps.pdf(d), e = table.pdf(d);
      if (p > 0 && e > 0) worst = std::min(worst, double(p) / e);
    }
  }
  return worst;
}
}  // namespace

TEST(ProductSampler, EnvironmentFloorBoundsTheDensityByTheEnvironments) {
  // The documented guarantee: wherever the product samples (pdf > 0), its density is at least
  // r / (1 + r) of the environment table's, over random shading points and every test map. Without the
  // floor (r = 0) glossy proxies break it by far, so the test can tell.
  for (const auto& [name, table] : test_tables()) {
    for (float r : {ProductSamplerOptions{}.env_floor, 0.0f}) {
      ProductSamplerOptions o;
      o.env_floor = r;
      ProductSampler ps(*table, o);
      const double worst = worst_density_ratio(ps, *table, random_configs(60, 17), 21);
      if (r > 0)
        EXPECT_GE(worst, r / (1 + r) * (1 - 1e-4)) << name;
      else
        EXPECT_LT(worst, 0.5 * ProductSamplerOptions{}.env_floor) << name;
    }
  }
}

// ---- The refined sampler: the sub-cell chosen by the product too (tables with sub-cells).

namespace {
std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> refined_tables() {
  std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> t;
  ImportanceTableOptions o;
  o.subdivision = 4;
  t.emplace_back("synthetic sky S=4", std::make_shared<ImportanceTable>(synthetic_sky(256, 128), o));
  // A sun of a few texels on a sub-cell corner of the equal-area square, and one at a pole: the
  // adversarial cases for a level that chooses among small regions.
  // An equal-area map: its texels line up with the square, so the sun sits exactly where intended.
  EnvironmentMapOptions ea;
  ea.layout = MapLayout::EqualArea;
  for (const Point2 at : {Point2{0.25f, 0.5f}, Point2{0.5f, 0.5f}}) {
    o.subdivision = at.x == 0.5f ? 2 : 8;
    t.emplace_back("tiny sun S=" + std::to_string(o.subdivision),
                   std::make_shared<ImportanceTable>(synthetic_latlong(128, 128, [&](int x, int y) {
                     const bool sun = std::abs(x + 0.5f - at.x * 128) < 1.5f && std::abs(y + 0.5f - at.y * 128) < 1.5f;
                     return sun ? 5e4f : 0.2f;
                   }, ea), o));
  }
  o.subdivision = 4;
  if (have_blender_maps())
    for (const char* name : {"sunset", "studio"})
      t.emplace_back(std::string(name) + " S=4", std::make_shared<ImportanceTable>(EnvironmentMap::load(blender_map(name)), o));
  return t;
}

ProductSamplerOptions refined() {
  ProductSamplerOptions o;
  o.refine = true;
  return o;
}
}  // namespace

TEST(ProductSampler, RefinedChiSquareOverManyConfigurations) {
  const auto tables = refined_tables();
  const int per_table = 10;
  const int tests = per_table * int(tables.size());
  int k = 0;
  // Half the configurations re-weigh the heaviest top cells from their sub-cells, half do not.
  ProductSamplerOptions heavy = refined(), lazy = refined();
  heavy.refine_cells = 8;
  lazy.refine_cells = 0;
  for (const auto& [name, table] : tables) {
    ProductSampler heavy_ps(*table, heavy), lazy_ps(*table, lazy);
    ASSERT_TRUE(heavy_ps.refines() && lazy_ps.refines());
    for (const Config& c : random_configs(per_table, 300 + k)) {
      ProductSampler& ps = k % 2 ? lazy_ps : heavy_ps;
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy)) << name << " " << c.label;
      const auto r = product_chi2(ps, 3000 + k++, tests);
      EXPECT_TRUE(r.passed) << name << " " << c.label << ": " << r.message;
    }
  }
  EXPECT_GE(k, 30);
}

// Over MIS-compensated tables (the renderer's --product-compensation on): most of the sphere has no
// environment importance there, so the product is zero on whole cells and sub-cells, and a proxy that
// sees none of the rest falls back to the compensated environment alone.
TEST(ProductSampler, CompensatedTableChiSquare) {
  ImportanceTableOptions o;
  o.subdivision = 4;
  o.compensated = true;
  std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> tables;
  tables.emplace_back("synthetic sky, compensated", std::make_shared<ImportanceTable>(synthetic_sky(256, 128), o));
  tables.emplace_back("tiny sun, compensated", std::make_shared<ImportanceTable>(synthetic_latlong(128, 64, [](int x, int y) {
                        return x == 40 && y == 20 ? 5e4f : 0.2f + 0.01f * float(y);
                      }), o));
  if (have_blender_maps())
    tables.emplace_back("sunset, compensated", std::make_shared<ImportanceTable>(EnvironmentMap::load(blender_map("sunset")), o));
  const int per_table = 6;
  const int tests = per_table * int(tables.size());
  int k = 0;
  for (const auto& [name, table] : tables) {
    ProductSampler ps(*table, refined());
    for (const Config& c : random_configs(per_table, 500 + k)) {
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy)) << name << " " << c.label;
      const auto r = product_chi2(ps, 5000 + k++, tests);
      EXPECT_TRUE(r.passed) << name << " " << c.label << ": " << r.message;
    }
  }
  EXPECT_GE(k, 12);
}

TEST(ProductSampler, RefinedSamplePdfAgreeAndInvertRoundTrips) {
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<float> U(0, 1);
  int k = 0;
  for (const auto& [name, table] : refined_tables()) {
    ProductSampler ps(*table, refined());
    for (const Config& c : random_configs(5, 70 + k++)) {
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy));
      int far = 0;
      const int n = 4000;
      for (int i = 0; i < n; ++i) {
        const Point2 u{U(rng), U(rng)};
        const DirectionSample s = ps.sample(u);
        ASSERT_GT(s.pdf, 0.0f) << name << " " << c.label;
        ASSERT_TRUE(std::isfinite(s.pdf));
        ASSERT_NEAR(s.pdf, ps.pdf(s.direction), 1e-4f * s.pdf) << name << " " << c.label;
        // Where one texel holds most of u's range (the tiny suns), the mapping's round-off moves v
        // away from u by that texel's stretch; sample(v) must still come back to the direction.
        const Point2 v = ps.invert(s.direction);
        if ((std::fabs(v.x - u.x) > 1e-3f || std::fabs(v.y - u.y) > 1e-3f) &&
            dot(ps.sample(v).direction, s.direction) < std::cos(1e-3f))
          ++far;
      }
      EXPECT_LT(far, n / 200) << name << " " << c.label << ": samples whose inverse is not their u";
      // The sub-cell distributions the sampler uses are valid wherever the top level samples.
      for (int cell = 0; cell < table->cell_count(); ++cell)
        if (ps.cell_probability(cell) > 0) ASSERT_TRUE(ps.subcells(cell).valid()) << name << " cell " << cell;
    }
  }
}

// pdf_square(p) is pdf() of p's direction: the same bits wherever the round trip square -> sphere ->
// square stays in p's texel (every point kept 1e-3 of a texel from its edges), for the table and the
// product sampler, and on a table with the map's own texels; 0 outside the square or at NaN. On the
// equal-area tables pdf_texel, the density of a texel given by its index, is pdf_square of its points.
TEST(ProductSampler, PdfSquareIsThePdfOfItsDirection) {
  std::mt19937_64 rng(47);
  std::uniform_real_distribution<float> U(0, 1);
  auto tables = refined_tables();
  ImportanceTableOptions map_texels;
  map_texels.fine_texels = FineTexels::Map;
  map_texels.subdivision = 2;
  tables.emplace_back("map texels", std::make_shared<ImportanceTable>(synthetic_sky(256, 128), map_texels));
  int k = 0;
  for (const auto& [name, table] : tables) {
    ProductSampler ps(*table, refined());
    // (A table on the map's texels has no equal-area grid: any grid serves, p's direction decides.)
    const float n = table->fine_texels() == FineTexels::Map ? 256.0f : float(table->fine_resolution());
    for (const Config& c : random_configs(3, 90 + k++)) {
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy));
      int positive = 0;
      for (int i = 0; i < 20000; ++i) {
        // A point of a random texel, away from the texel's edges.
        const Point2 p{(std::floor(U(rng) * n) + 1e-3f + 0.998f * U(rng)) / n,
                       (std::floor(U(rng) * n) + 1e-3f + 0.998f * U(rng)) / n};
        const Vec3 d = equal_area_square_to_sphere(p);
        ASSERT_EQ(ps.pdf_square(p), ps.pdf(d)) << name << " " << c.label << " at " << p.x << ", " << p.y;
        ASSERT_EQ(table->pdf_square(p), table->pdf(d)) << name << " at " << p.x << ", " << p.y;
        if (table->fine_texels() == FineTexels::EqualArea) {  // the texel's density, located by its index
          const int x = static_cast<int>(p.x * n), y = static_cast<int>(p.y * n);
          ASSERT_EQ(ps.pdf_texel(x, y), ps.pdf_square(p)) << name << " " << c.label << " texel " << x << ", " << y;
          ASSERT_EQ(table->pdf_texel(x, y), table->pdf_square(p)) << name << " texel " << x << ", " << y;
        }
        positive += ps.pdf_square(p) > 0;
      }
      EXPECT_GT(positive, 1000) << name << " " << c.label;  // not a comparison of zeros
    }
    for (const Point2 bad : {Point2{-0.1f, 0.5f}, Point2{0.5f, 1.5f}, Point2{std::nanf(""), 0.5f}}) {
      EXPECT_EQ(ps.pdf_square(bad), 0.0f) << name;
      EXPECT_EQ(table->pdf_square(bad), 0.0f) << name;
    }
    for (const auto& [x, y] : {std::pair{-1, 0}, std::pair{0, table->fine_resolution()}}) {
      EXPECT_EQ(ps.pdf_texel(x, y), 0.0f) << name;
      EXPECT_EQ(table->pdf_texel(x, y), 0.0f) << name;
    }
  }
}

// Refinement moves samples inside cells towards the lobe: for a narrow lobe under a uniform sky, the
// refined density at the lobe's axis is higher than the paper's (which is uniform inside the cell).
TEST(ProductSampler, RefinementConcentratesOnANarrowLobe) {
  ImportanceTableOptions o;
  o.subdivision = 4;
  const ImportanceTable table(synthetic_latlong(64, 32, [](int, int) { return 1.0f; }), o);
  ProductSamplerOptions one = refined(), two = refined();
  one.cell_estimate = two.cell_estimate = CellEstimate::Cone;  // the cells whose cones graze the lobe
  one.refine = false;
  two.refine_cells = 8;
  one.proxy.min_alpha = two.proxy.min_alpha = 0.0f;  // the lobe as narrow as the BSDF's
  ProductSampler paper(table, one), refined_sampler(table, two);
  EXPECT_FALSE(paper.refines());
  BsdfProxy proxy;
  proxy.add_reflection(1.0f, 0.05f);
  const Vec3 n{0, 0, 1}, wo = normalize(Vec3{0.3f, 0.1f, 1});
  ASSERT_TRUE(paper.prepare(n, wo, proxy));
  ASSERT_TRUE(refined_sampler.prepare(n, wo, proxy));
  const Vec3 r = n * (2 * dot(wo, n)) - wo;
  EXPECT_GT(refined_sampler.pdf(r), 2.0f * paper.pdf(r));
  // The paper's density inside a cell follows the environment only: uniform here.
  const int c = table.cell_of_direction(r);
  EXPECT_NEAR(paper.pdf(r), paper.cell_probability(c) * table.cell_count() * kInv4Pi, 1e-3f * paper.pdf(r));
  // Re-weighing the heaviest cells from their sub-cells moves probability towards the cell that holds
  // the lobe's axis, away from neighbours whose cones only graze it; without it (refine_cells 0) the
  // top level is the paper's.
  EXPECT_GT(refined_sampler.cell_probability(c), 1.2f * paper.cell_probability(c));
  two.refine_cells = 0;
  ProductSampler lazy(table, two);
  ASSERT_TRUE(lazy.prepare(n, wo, proxy));
  for (int k = 0; k < table.cell_count(); ++k) ASSERT_EQ(lazy.cell_probability(k), paper.cell_probability(k));
}

TEST(ProductSampler, RefinedNeedsSubcellsAndDoesNotAllocate) {
  const ImportanceTable flat(synthetic_sky(64, 32));
  EXPECT_THROW(ProductSampler(flat, refined()), Error);
  ImportanceTableOptions o;
  o.subdivision = 4;
  const ImportanceTable table(synthetic_sky(), o);
  ProductSampler ps(table, refined());
  expect_no_allocation(ps);
}

TEST(ProductSampler, RefinedFloorBoundsTheDensityByTheEnvironments) {
  // The documented guarantee with both floors: at least (r / (1 + r))^2 of the environment's density
  // wherever the refined product samples, with either cell estimate (the moments are an estimate, not
  // a bound: the floors are what keeps the tail); without the floors glossy proxies break it by far.
  const float r0 = ProductSamplerOptions{}.env_floor;
  const double bound0 = (r0 / (1 + r0)) * (r0 / (1 + r0));
  for (CellEstimate estimate : {CellEstimate::Cone, CellEstimate::Moments}) {
    double worst_unfloored = HUGE_VAL;
    for (const auto& [name, table] : refined_tables()) {
      for (float r : {ProductSamplerOptions{}.env_floor, 0.0f}) {
        ProductSamplerOptions o = refined();
        o.cell_estimate = estimate;
        o.env_floor = r;
        o.refine_cells = r > 0 ? 8 : 0;  // both ways of weighing sub-cells, each bounded
        ProductSampler ps(*table, o);
        const double worst = worst_density_ratio(ps, *table, random_configs(40, 18), 22);
        if (r > 0)
          EXPECT_GE(worst, bound0 * (1 - 1e-4)) << name << " " << to_string(estimate);
        else
          worst_unfloored = std::min(worst_unfloored, worst);
      }
    }
    EXPECT_LT(worst_unfloored, bound0) << to_string(estimate);  // without the floors it does not hold
  }
}

// ---- The moments estimate (CellEstimate::Moments): each cell's proxy at its importance-weighted mean
// direction (the cosine lobes from it and its spread).

namespace {
ProductSamplerOptions moments(bool refine) {
  ProductSamplerOptions o;
  o.refine = refine;
  o.cell_estimate = CellEstimate::Moments;
  return o;
}

// The tables of both sets (the adversarial tiny suns on a corner and at the pole among them).
std::vector<std::pair<std::string, std::shared_ptr<ImportanceTable>>> all_tables() {
  auto t = test_tables();
  for (auto& r : refined_tables()) t.push_back(r);
  return t;
}
}  // namespace

TEST(ProductSampler, MomentsChiSquareOverManyConfigurations) {
  const auto tables = all_tables();
  const int per_table = 8;
  const int tests = per_table * int(tables.size());
  int k = 0;
  for (const auto& [name, table] : tables) {
    // One-level and refined (on tables with sub-cells), alternating.
    // Every third with the half-vector reflection lobe.
    ProductSampler one(*table, moments(false));
    ProductSamplerOptions half_opt = moments(table->subdivision() > 1);
    half_opt.proxy.reflection_lobe = ReflectionLobe::HalfVector;
    ProductSampler half(*table, half_opt);
    std::unique_ptr<ProductSampler> two;
    if (table->subdivision() > 1) two = std::make_unique<ProductSampler>(*table, moments(true));
    for (const Config& c : random_configs(per_table, 500 + k)) {
      ProductSampler& ps = k % 3 == 2 ? half : two && k % 2 ? *two : one;
      ASSERT_TRUE(ps.prepare(c.n, c.wo, c.proxy)) << name << " " << c.label;
      const auto r = product_chi2(ps, 5000 + k++, tests);
      EXPECT_TRUE(r.passed) << name << " " << c.label << ": " << r.message;
    }
  }
  EXPECT_GE(k, 50);
}

// The moments estimate weighs exactly the cells the cone estimate weighs (the same horizon gates; the
// lobes' tails keep every other cell positive), so it samples everywhere the paper's sampler does.
TEST(ProductSampler, MomentsEstimatePositiveWhereTheConeIs) {
  for (const auto& [name, table] : all_tables()) {
    ProductSamplerOptions cone_opt, moment_opt = moments(false);
    cone_opt.cell_estimate = CellEstimate::Cone;
    cone_opt.env_floor = moment_opt.env_floor = 0;
    ProductSampler cone(*table, cone_opt), moment(*table, moment_opt);
    for (const Config& c : random_configs(40, 31)) {
      ASSERT_TRUE(cone.prepare(c.n, c.wo, c.proxy));
      ASSERT_TRUE(moment.prepare(c.n, c.wo, c.proxy));
      for (int i = 0; i < table->cell_count(); ++i)
        ASSERT_EQ(cone.cell_probability(i) > 0, moment.cell_probability(i) > 0) << name << " " << c.label << " cell " << i;
    }
  }
}

// What the estimate is for: the top level's share of each cell should follow the cell's true mass
// M_c = sum over its fine texels of importance x proxy. Measured by the cell-level variance factor
// sum_c M_c^2 / p_c / (sum M)^2 (1: cells chosen exactly by their mass): geometric mean over random
// proxies, lower with the moments than with the cones on every table.
TEST(ProductSampler, MomentsEstimateFollowsTheCellMassesBetter) {
  for (const auto& [name, table] : all_tables()) {
    const int N = table->fine_resolution(), T = table->top_resolution();
    if (N > 512) continue;  // the quadrature below visits every fine texel per proxy
    ProductSamplerOptions cone_opt, moment_opt = moments(false);
    cone_opt.cell_estimate = CellEstimate::Cone;
    cone_opt.env_floor = moment_opt.env_floor = 0;
    ProductSampler cone(*table, cone_opt), moment(*table, moment_opt);
    double log_cone = 0, log_moment = 0;
    int n = 0;
    for (const Config& c : random_configs(24, 41)) {
      ASSERT_TRUE(cone.prepare(c.n, c.wo, c.proxy));
      ASSERT_TRUE(moment.prepare(c.n, c.wo, c.proxy));
      const PreparedProxy& pp = cone.prepared_proxy();
      std::vector<double> mass(table->cell_count(), 0.0);
      double total = 0;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const Vec3 d = equal_area_square_to_sphere({(x + 0.5f) / N, (y + 0.5f) / N});
          const double m = double(table->importance(x, y)) * pp.eval(d);
          mass[(y / (N / T)) * T + x / (N / T)] += m;
          total += m;
        }
      if (!(total > 0)) continue;
      double vc = 0, vm = 0;
      for (int i = 0; i < table->cell_count(); ++i) {
        if (mass[i] == 0) continue;
        const double m = mass[i] / total;
        vc += m * m / cone.cell_probability(i);
        vm += m * m / moment.cell_probability(i);
      }
      log_cone += std::log(vc);
      log_moment += std::log(vm);
      ++n;
    }
    ASSERT_GT(n, 10) << name;
    const double gc = std::exp(log_cone / n), gm = std::exp(log_moment / n);
    std::printf("%s: cell-level variance factor, cone %.4f, moments %.4f\n", name.c_str(), gc, gm);
    EXPECT_LT(gm, gc) << name;
    EXPECT_GE(gm, 1.0 - 1e-6) << name;  // no distribution beats the masses themselves
  }
}

// Every kernel set gives the scalar kernels' weights, for both cell estimates and both reflection lobes.
TEST(ProductSampler, MomentsKernelsMatchTheScalarKernels) {
  const std::vector<const detail::Kernels*> sets = detail::kernels_available();
  const detail::Kernels& ref = detail::kernels_scalar();
  for (const auto& [name, table] : all_tables()) {
    const detail::CellArrays cells = detail::cell_arrays(*table);
    std::vector<float> expected(cells.padded_count), got(cells.padded_count);
    int i = 0;
    for (const Config& c : random_configs(30, 19)) {
      ProxyOptions po;  // both reflection lobes, both estimates
      if (i % 2) po.reflection_lobe = ReflectionLobe::HalfVector;
      const PreparedProxy pp = prepare_proxy(c.proxy, c.n, c.wo, po);
      ASSERT_TRUE(pp.valid());
      detail::LobeParams lobes = detail::to_lobe_params(pp);
      lobes.moments = i++ % 4 < 2;
      ref.product_weights(cells, lobes, expected.data());
      double total = 0;
      for (float w : expected) {
        ASSERT_TRUE(std::isfinite(w) && w >= 0) << name << " " << c.label;
        total += w;
      }
      ASSERT_GT(total, 0) << name << " " << c.label;
      for (const detail::Kernels* k : sets) {
        const float returned = k->product_weights(cells, lobes, got.data());
        expect_returned_total(returned, got, k->name);
        for (int i = 0; i < cells.padded_count; ++i)
          ASSERT_NEAR(got[i], expected[i], 2e-3 * std::max(double(expected[i]), 1e-6 * total))
              << k->name << " " << name << " " << c.label << " cell " << i;
      }
    }
  }
}

TEST(ProductSampler, MomentsDoNotAllocate) {
  ImportanceTableOptions o;
  o.subdivision = 4;
  const ImportanceTable flat(synthetic_sky()), table(synthetic_sky(), o);
  ProductSampler one(flat, moments(false)), two(table, moments(true));
  expect_no_allocation(one);
  expect_no_allocation(two);
  EXPECT_EQ(to_string(parse_cell_estimate("moments")), std::string("moments"));
  EXPECT_EQ(parse_cell_estimate("cone"), CellEstimate::Cone);
  EXPECT_THROW(parse_cell_estimate("centroid"), Error);
}
