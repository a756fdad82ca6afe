// SPDX-License-Identifier: Apache-2.0
// Correctness tests of the renderer (render/render.h, render/strategy.h, render/scenes.h):
//   - every strategy converges to the same per-sphere means on a small fig1 as a high-sample reference
//     rendered with a different strategy (z-test, Bonferroni-corrected),
//   - no NaN/Inf pixel with either integrator,
//   - identical images for the same seed at 1 and 2 threads, and prefix images (fewer spp) bit-identical to those renders,
//   - white furnace (white Lambert and non-absorbing dielectric spheres under a constant white sky),
//   - light samplers: sample() and pdf() agree, and the oracle / product densities integrate to 1,
//   - the command's option validation (scene files: test_scene_file.cpp).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "cli_util.h"
#include "test_util.h"
#include "render/render.h"
#include "render/sampler.h"
#include "render/scenes.h"
#include "test_sky.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;

const Scene& small_fig1() {
  static const Scene scene = make_builtin_scene("fig1", test_sky());
  return scene;
}

RenderOptions small_options(Strategy s, int spp, std::uint64_t seed) {
  RenderOptions o;
  o.strategy = s;
  o.integrator = IntegratorKind::Direct;
  o.spp = spp;
  o.seed = seed;
  o.width = 96;
  o.height = 16;
  o.oracle.resolution = 16;  // the full 64 x 64 oracle is too slow for a unit test
  o.oracle.directions = 4;
  return o;
}

bool all_finite(const RenderResult& r) {
  for (float v : r.rgb)
    if (!std::isfinite(v)) return false;
  return true;
}

TEST(Scenes, Fig1ObjectIdsAreEightSpheresLeftToRight) {
  const Scene& s = small_fig1();
  ASSERT_EQ(s.objects().size(), 8u);
  RenderOptions o = small_options(Strategy::Bsdf, 1, 0);
  o.width = 768;
  o.height = 128;
  const RenderResult r = render(s, o);
  // Along the middle row the ids go -1, 0, -1, 1, ..., 7, -1.
  std::vector<int> seq;
  for (int x = 0; x < r.width; ++x) {
    const int id = r.object_id[static_cast<std::size_t>(r.height / 2) * r.width + x];
    if (id >= 0 && (seq.empty() || seq.back() != id)) seq.push_back(id);
  }
  EXPECT_EQ(seq, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  const auto means = object_means(r, 8);
  for (const auto& m : means) EXPECT_GT(m.pixels, 500u) << s.objects()[m.object].name;
}

// Two-sided, family-wise 1e-3 over `tests` z-tests (Bonferroni): |z| < Phi^-1(1 - 5e-4 / tests).
double bonferroni_z(int tests) {
  const double alpha = 1e-3 / tests;
  double z_max = 0;  // solve erfc(z / sqrt 2) = alpha by bisection
  for (double lo = 0, hi = 10, i = 0; i < 100; ++i, z_max = lo) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  return z_max;
}

// Every strategy converges to the same per-sphere means as a reference from another strategy.
TEST(Convergence, EveryStrategyMatchesReferencePerSphere) {
  const Scene& scene = small_fig1();
  const int spheres = 8;
  // Two references (2048 spp), so that no strategy is compared with itself.
  const RenderResult ref_mis = render(scene, small_options(Strategy::Mis, 2048, 1000));
  const RenderResult ref_product = render(scene, small_options(Strategy::Product, 2048, 2000));
  const auto m_mis = object_means(ref_mis, spheres), m_product = object_means(ref_product, spheres);

  const int tests = static_cast<int>(all_strategies().size()) * spheres;
  const double z_max = bonferroni_z(tests);
  std::printf("Bonferroni threshold |z| < %.2f over %d tests\n", z_max, tests);
  std::printf("%-9s", "strategy");
  for (int i = 0; i < spheres; ++i) std::printf(" %15s", fig1_sphere_names()[i].c_str());
  std::printf("\n");
  for (Strategy s : all_strategies()) {
    // env alone meets the near-mirror lobes only by chance (a heavy-tailed estimator whose sample
    // variance is unreliable at a few hits per sphere): give it more samples; it is cheap.
    const int spp = s == Strategy::Oracle ? 32 : (s == Strategy::Env ? 1024 : 64);
    const RenderResult r = render(scene, small_options(s, spp, 42));
    ASSERT_EQ(r.nonfinite_pixels, 0u) << to_string(s);
    ASSERT_TRUE(all_finite(r));
    const auto m = object_means(r, spheres);
    const auto& ref = s == Strategy::Mis ? m_product : m_mis;
    std::printf("%-9s", to_string(s));
    for (int i = 0; i < spheres; ++i) {
      ASSERT_GT(m[i].pixels, 20u);
      const double se = std::sqrt(m[i].variance + ref[i].variance);
      ASSERT_GT(se, 0.0);
      const double z = (m[i].mean - ref[i].mean) / se;
      std::printf(" %7.4f(%+5.2f)", m[i].mean, z);
      EXPECT_LT(std::fabs(z), z_max) << to_string(s) << " sphere " << fig1_sphere_names()[i] << ": mean "
                                     << m[i].mean << " vs reference " << ref[i].mean;
    }
    std::printf("\n");
  }
  // The references agree with each other too.
  for (int i = 0; i < spheres; ++i) {
    const double z = (m_mis[i].mean - m_product[i].mean) / std::sqrt(m_mis[i].variance + m_product[i].variance);
    EXPECT_LT(std::fabs(z), z_max) << "references disagree on " << fig1_sphere_names()[i];
  }
}

// product with the compensated table, at its own vertices (on) or at the others (elsewhere: below
// --product-max-roughness, here every sphere rougher than alpha 0.1 and the diffuse one), converges to
// mis's per-sphere means: directions the compensated table leaves at zero are the BSDF sample's alone.
TEST(Convergence, CompensatedProductMatchesReferencePerSphere) {
  const Scene& scene = small_fig1();
  const int spheres = 8;
  const auto ref = object_means(render(scene, small_options(Strategy::Mis, 2048, 1000)), spheres);
  const double z_max = bonferroni_z(2 * spheres);
  for (ProductCompensation pc : {ProductCompensation::Elsewhere, ProductCompensation::On}) {
    RenderOptions o = small_options(Strategy::Product, 128, 42);
    o.product_compensation = pc;
    o.product_max_roughness = 0.1f;
    o.product_cache.entries = 0;  // without the cache the camera rays' hits follow the rule too
    const RenderResult r = render(scene, o);
    ASSERT_EQ(r.nonfinite_pixels, 0u);
    const auto m = object_means(r, spheres);
    for (int i = 0; i < spheres; ++i) {
      const double z = (m[i].mean - ref[i].mean) / std::sqrt(m[i].variance + ref[i].variance);
      EXPECT_LT(std::fabs(z), z_max) << to_string(pc) << " sphere " << fig1_sphere_names()[i] << ": mean "
                                     << m[i].mean << " vs reference " << ref[i].mean;
    }
  }
}

TEST(Robustness, NoNonFinitePixelsWithThePathIntegrator) {
  for (Strategy s : all_strategies()) {
    RenderOptions o = small_options(s, s == Strategy::Oracle ? 2 : 8, 5);
    o.integrator = IntegratorKind::Path;
    o.heuristic = Heuristic::Balance;
    const RenderResult r = render(small_fig1(), o);
    EXPECT_EQ(r.nonfinite_pixels, 0u) << to_string(s);
    EXPECT_TRUE(all_finite(r)) << to_string(s);
  }
}

TEST(Determinism, SameSeedSameImageAtOneAndTwoThreads) {
  for (Strategy s : {Strategy::Mis, Strategy::Product, Strategy::Oracle}) {
    RenderOptions o = small_options(s, s == Strategy::Oracle ? 2 : 8, 77);
    o.integrator = IntegratorKind::Path;
    o.tile_size = 8;
    RenderResult one, two;
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
      one = render(small_fig1(), o);
    }
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
      two = render(small_fig1(), o);
    }
    EXPECT_EQ(one.rgb, two.rgb) << to_string(s);
    EXPECT_EQ(one.variance, two.variance) << to_string(s);
    o.seed = 78;
    const RenderResult other = render(small_fig1(), o);
    EXPECT_NE(one.rgb, other.rgb) << to_string(s);
  }
}


// The prefix images (compare's convergence series) are the images of renders at fewer spp, bit for bit.
TEST(Determinism, PrefixImagesAreTheRendersAtFewerSamples) {
  RenderOptions o = small_options(Strategy::Product, 8, 5);
  o.integrator = IntegratorKind::Path;
  o.prefix_spp = {1, 3};
  const RenderResult full = render(small_fig1(), o);
  ASSERT_EQ(full.prefixes.size(), 2u);
  o.prefix_spp.clear();
  EXPECT_EQ(render(small_fig1(), o).rgb, full.rgb);
  for (std::size_t k = 0; k < full.prefixes.size(); ++k) {
    const RenderResult p = full.prefix(k);
    o.spp = p.spp;
    const RenderResult r = render(small_fig1(), o);
    EXPECT_EQ(r.rgb, p.rgb) << p.spp;
    EXPECT_EQ(r.variance, p.variance) << p.spp;
    EXPECT_EQ(r.light_variance, p.light_variance) << p.spp;
    EXPECT_EQ(r.object_id, p.object_id) << p.spp;
    EXPECT_EQ(r.samples, p.samples) << p.spp;
    EXPECT_NE(r.rgb, full.rgb) << p.spp;
  }
  for (const std::vector<int>& bad : {std::vector<int>{0}, {8}, {2, 2}, {3, 1}}) {
    o.spp = 8;
    o.prefix_spp = bad;
    EXPECT_THROW(render(small_fig1(), o), Error);
  }
}
// White furnace: under a constant unit environment, a white Lambert sphere and a non-absorbing
// (nearly smooth) dielectric sphere are invisible (radiance 1 everywhere) with the path integrator.
TEST(Furnace, WhiteLambertAndClearDielectricSpheresAreInvisible) {
  Scene s;
  Material white, glass;
  white.add(make_lambert({1, 1, 1}));
  // Nearly smooth: a rough GGX dielectric loses its single-scattering energy at every interface
  // (about 2% through a sphere at alpha 0.05, 27% at 0.3; see tests/render/test_materials.cpp).
  glass.add(make_dielectric(0.01f, 1.5f));
  s.add_material("white", std::move(white), false);
  s.add_material("glass", std::move(glass), true);
  s.add_sphere("white", {-1.2f, 0, 0}, 1.0f, 0);
  s.add_sphere("glass", {1.2f, 0, 0}, 1.0f, 1);
  s.set_camera(look_at({0, -20, 0}, {0, 0, 0}, 7.5f, 64, 32));
  s.set_environment(std::make_shared<const EnvironmentMap>(make_constant_environment({1, 1, 1})));
  s.commit();
  for (Strategy st : {Strategy::Bsdf, Strategy::Mis, Strategy::Product}) {
    RenderOptions o;
    o.strategy = st;
    o.integrator = IntegratorKind::Path;
    o.max_depth = 64;
    o.spp = 64;
    o.seed = 3;
    const RenderResult r = render(s, o);
    const auto m = object_means(r, 2);
    for (int i = 0; i < 2; ++i) {
      const double se = std::sqrt(m[i].variance);
      EXPECT_NEAR(m[i].mean, 1.0, 0.004 + 4 * se) << to_string(st) << " " << s.objects()[i].name;
    }
    // Lambert: every camera sample is exactly 1 only in expectation; its mean must be very close.
    EXPECT_NEAR(m[0].mean, 1.0, 0.01) << to_string(st);
  }
}

/// Shading context on a fig1-like material, for the light-sampler tests.
struct TestPoint {
  Material bsdf;
  Frame frame;
  ShadingContext sc;
  TestPoint(std::shared_ptr<const Lobe> lobe, Vec3 n, Vec3 wo) : frame(normalize(n)) {
    bsdf.add(std::move(lobe));
    sc.n = frame.n;
    sc.wo = normalize(wo);
    sc.wo_local = frame.to_local(sc.wo);
    sc.frame = &frame;
    sc.bsdf = &bsdf;
    sc.jitter = 0x1234567887654321ULL;
    sc.opaque = true;
  }
};

TEST(LightSampler, SampleAndPdfAgreeAndIntegrateToOne) {
  const EnvironmentMap& env = *test_sky();
  for (Strategy s : {Strategy::Env, Strategy::Mis, Strategy::MisComp, Strategy::Product, Strategy::Oracle}) {
    OracleOptions oo;
    oo.resolution = 16;
    const StrategyTables t = StrategyTables::build(env, s, oo);
    LightSampler ls(t);
    TestPoint tp(make_conductor_reflectance(0.2f, {0.9f, 0.9f, 0.9f}), {0.3f, -0.8f, 0.4f}, {0.1f, -1.0f, 0.3f});
    ls.prepare(tp.sc);
    PixelSampler rng(SamplerKind::Independent, 1, 2, 3);
    int valid = 0;
    for (int i = 0; i < 2000; ++i) {
      const DirectionSample d = ls.sample(rng.next2d());
      if (d.pdf <= 0) continue;
      ++valid;
      EXPECT_NEAR(length(d.direction), 1.0f, 1e-4f);
      EXPECT_NEAR(ls.pdf(d.direction), d.pdf, 1e-3f * d.pdf) << to_string(s);
    }
    EXPECT_GT(valid, 1900) << to_string(s);
    // Integral of pdf over the sphere by midpoint quadrature on a fine equal-area grid.
    const int n = 512;
    double integral = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        integral += ls.pdf(equal_area_square_to_sphere({(x + 0.5f) / n, (y + 0.5f) / n}));
    integral *= 4.0 * kPi / (double(n) * n);
    EXPECT_NEAR(integral, 1.0, 0.01) << to_string(s);
  }
}

// One compensation mode: product's density at glossy vertices, `elsewhere`'s at the others.
void check_one_density_per_vertex(const EnvironmentMap& env, ProductCompensation pc, const ImportanceTable& elsewhere) {
  SCOPED_TRACE(std::string("compensation ") + to_string(pc));
  StrategyTables t = StrategyTables::build(env, Strategy::Product, {}, {}, {}, pc);
  const bool deeper = pc == ProductCompensation::Deeper;
  ASSERT_EQ(t.elsewhere_table != nullptr, pc == ProductCompensation::Elsewhere || deeper);
  t.product_max_roughness = 0.1f;
  const Vec3 n{0.3f, -0.8f, 0.4f}, wo{0.1f, -1.0f, 0.3f};
  TestPoint glossy(make_conductor_reflectance(0.05f, {0.9f, 0.9f, 0.9f}), n, wo);
  TestPoint rough(make_conductor_reflectance(0.3f, {0.9f, 0.9f, 0.9f}), n, wo);
  TestPoint diffuse(make_lambert({0.8f, 0.8f, 0.8f}), n, wo);
  TestPoint bent(make_conductor_reflectance(0.08f, {0.9f, 0.9f, 0.9f}), n, wo);
  bent.sc.cos_bent = 0.9f;  // widened to alpha 0.19: beyond the threshold, as product would see it
  TestPoint diffuse_first = diffuse;  // a camera ray's hit: product with the cache, whatever the lobe
  diffuse_first.sc.frame = &diffuse_first.frame;
  diffuse_first.sc.bsdf = &diffuse_first.bsdf;
  glossy.sc.depth = 3;  // below the first hit, the rule is by material, not depth
  diffuse.sc.depth = rough.sc.depth = bent.sc.depth = 1;
  struct Case {
    const TestPoint* point;
    bool product_with_cache, product_without;
  };
  const Case cases[] = {{&glossy, true, true},        {&diffuse, false, false}, {&rough, false, false},
                        {&diffuse_first, true, false}, {&glossy, true, true},    {&bent, false, false},
                        {&diffuse_first, true, false}};
  for (std::size_t cache : {std::size_t{16}, std::size_t{0}}) {
    t.product_cache.entries = static_cast<int>(cache);
    LightSampler ls(t);
    PixelSampler rng(SamplerKind::Independent, 1, 2, 3);
    for (const Case& c : cases) {
      SCOPED_TRACE("case " + std::to_string(&c - cases) + ", cache " + std::to_string(cache));
      const bool product = cache > 0 ? c.product_with_cache : c.product_without;
      ls.prepare(c.point->sc);
      ASSERT_EQ(ls.product_sampler() != nullptr, product);
      // Deeper: the plain table's product at a camera ray's hit, the compensated one's below it.
      if (product && deeper)
        EXPECT_EQ(&ls.product_sampler()->table(), c.point->sc.depth > 0 ? t.elsewhere_table.get() : t.table.get());
      int valid = 0;
      for (int i = 0; i < 500; ++i) {
        const DirectionSample d = ls.sample(rng.next2d());
        if (!(d.pdf > 0)) continue;
        ++valid;
        const float expected = product ? ls.product_sampler()->pdf(d.direction) : elsewhere.pdf(d.direction);
        EXPECT_NEAR(d.pdf, expected, 1e-4f * expected);
        EXPECT_NEAR(ls.pdf(d.direction), expected, 1e-4f * expected);
      }
      EXPECT_GT(valid, 450);
    }
  }
}

// The second table is left out only where nothing would sample it: no deeper vertex and the cache
// taking every camera ray's hit (LightSampler::product_at); otherwise the compensation is kept.
TEST(LightSampler, TablesCompensationDropsOnlyTheUnsampledSecondTable) {
  using PC = ProductCompensation;
  EXPECT_EQ(tables_compensation(PC::Deeper, false, 16), PC::Off);
  EXPECT_EQ(tables_compensation(PC::Elsewhere, false, 16), PC::Off);
  EXPECT_EQ(tables_compensation(PC::Deeper, false, 0), PC::Deeper);  // rough hits sample the second table
  EXPECT_EQ(tables_compensation(PC::Deeper, true, 16), PC::Deeper);
  EXPECT_EQ(tables_compensation(PC::Elsewhere, true, 0), PC::Elsewhere);
  EXPECT_EQ(tables_compensation(PC::On, false, 16), PC::On);  // one table, the product's own
  EXPECT_EQ(tables_compensation(PC::Off, true, 0), PC::Off);
}

// on-without-portals (the envpis command's default along paths) is On for product and Off for
// product-portal; the strategies without a product never get a compensation; names round-trip.
TEST(LightSampler, CompensationForEachStrategy) {
  using PC = ProductCompensation;
  EXPECT_EQ(compensation_for(PC::OnWithoutPortals, Strategy::Product), PC::On);
  EXPECT_EQ(compensation_for(PC::OnWithoutPortals, Strategy::ProductPortal), PC::Off);
  EXPECT_EQ(compensation_for(PC::On, Strategy::ProductPortal), PC::On);
  EXPECT_EQ(compensation_for(PC::Deeper, Strategy::Product), PC::Deeper);
  for (Strategy s : {Strategy::Mis, Strategy::MisComp, Strategy::MisPortal, Strategy::Oracle})
    EXPECT_EQ(compensation_for(PC::On, s), PC::Off) << to_string(s);
  for (PC c : {PC::Off, PC::Elsewhere, PC::Deeper, PC::On, PC::OnWithoutPortals})
    EXPECT_EQ(parse_product_compensation(to_string(c)), c) << to_string(c);
  // "auto" is the command's, resolved by the integrator; the error names every value, the list the command's error extends.
  try {
    parse_product_compensation("auto");
    ADD_FAILURE() << "auto parsed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("(expected off, elsewhere, deeper, on or on-without-portals)"), std::string::npos) << e.what();
  }
  EXPECT_EQ(product_compensation_names("auto"), "off, elsewhere, deeper, on, on-without-portals or auto");
}

// product with --product-max-roughness: the distribution a vertex draws its light sample from is the
// one pdf() gives the BSDF sample's MIS weight at that vertex, product's at glossy vertices and the
// table's elsewhere (mis's, or mis-comp's with compensation), also when glossy and other vertices
// alternate (no stale product distribution).
TEST(LightSampler, ProductAtGlossyVerticesUsesOneDensityPerVertex) {
  const EnvironmentMap& env = *test_sky();
  const StrategyTables mis = StrategyTables::build(env, Strategy::Mis);
  const StrategyTables comp = StrategyTables::build(env, Strategy::MisComp);
  check_one_density_per_vertex(env, ProductCompensation::Off, *mis.table);
  check_one_density_per_vertex(env, ProductCompensation::Elsewhere, *comp.table);
  check_one_density_per_vertex(env, ProductCompensation::Deeper, *comp.table);
  check_one_density_per_vertex(env, ProductCompensation::On, *comp.table);
  // Infinity (the default): product at every vertex, the diffuse one too.
  StrategyTables t = StrategyTables::build(env, Strategy::Product);
  TestPoint diffuse(make_lambert({0.8f, 0.8f, 0.8f}), {0.3f, -0.8f, 0.4f}, {0.1f, -1.0f, 0.3f});
  diffuse.sc.depth = 1;
  t.product_max_roughness = kInfinity;
  LightSampler every(t);
  every.prepare(diffuse.sc);
  EXPECT_NE(every.product_sampler(), nullptr);
}

// With the product cache, a camera ray's hits share prepared distributions and deeper vertices are
// prepared exactly (their keys almost never repeat): a deeper point prepared twice is two misses, a
// first hit prepared twice one miss and one hit, and the deeper density is the exact sampler's.
TEST(LightSampler, ProductCacheServesFirstHitsOnly) {
  const EnvironmentMap& env = *test_sky();
  StrategyTables t = StrategyTables::build(env, Strategy::Product);
  t.product_cache.entries = 16;
  const Vec3 n{0.3f, -0.8f, 0.4f}, wo{0.1f, -1.0f, 0.3f};
  TestPoint first(make_conductor_reflectance(0.05f, {0.9f, 0.9f, 0.9f}), n, wo);
  TestPoint deeper = first;
  deeper.sc.frame = &deeper.frame;
  deeper.sc.bsdf = &deeper.bsdf;
  deeper.sc.depth = 2;
  LightSampler ls(t);
  ls.prepare(deeper.sc);
  ls.prepare(deeper.sc);
  EXPECT_EQ(ls.product_cache_hits(), 0u);
  EXPECT_EQ(ls.product_cache_misses(), 2u);
  ls.prepare(first.sc);
  ls.prepare(first.sc);
  EXPECT_EQ(ls.product_cache_hits(), 1u);
  EXPECT_EQ(ls.product_cache_misses(), 3u);

  t.product_cache.entries = 0;  // every point exactly: the deeper point's density must be this one
  LightSampler exact(t);
  exact.prepare(deeper.sc);
  ls.prepare(deeper.sc);
  PixelSampler rng(SamplerKind::Independent, 4, 5, 6);
  int valid = 0;
  for (int i = 0; i < 200; ++i) {
    const DirectionSample d = exact.sample(rng.next2d());
    if (!(d.pdf > 0)) continue;
    ++valid;
    EXPECT_EQ(ls.pdf(d.direction), exact.pdf(d.direction));  // the same distribution, bit for bit
  }
  EXPECT_GT(valid, 180);
}

// ---------------------------------------------------------------------------------------------
// Closed surfaces (render/scene.h): which transmissive materials get the closed-surface proxy

/// A cube of half-size 1 around c, two triangles per face, each face with its own four vertices
/// (so closedness needs the welding), counter-clockwise seen from outside unless `inward`.
TriangleMesh cube(Vec3 c, bool inward = false, int faces = 6) {
  TriangleMesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f}) {
      if (faces-- <= 0) return m;
      const auto base = static_cast<std::uint32_t>(m.positions.size());
      Vec3 n{0, 0, 0}, u{0, 0, 0}, v{0, 0, 0};
      (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = side;
      (axis == 0 ? u.y : axis == 1 ? u.z : u.x) = 1;
      v = cross(n, u);  // (u, v, n) right-handed: u x v = n, so (0, u, u+v) is counter-clockwise about n
      for (Vec3 q : {u * -1.0f + v * -1.0f, u - v, u + v, v - u}) m.positions.push_back(c + n + q);
      for (std::uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + k);
    }
  if (inward)
    for (std::size_t k = 0; k < m.indices.size(); k += 3) std::swap(m.indices[k + 1], m.indices[k + 2]);
  return m;
}

TEST(ClosedSurfaces, DetectedForSpheresAndClosedOutwardMeshesOnly) {
  const Scene& fig1 = small_fig1();
  for (int i = 0; i < fig1.material_count(); ++i) {
    const SceneMaterial& m = fig1.material(i);
    EXPECT_EQ(m.bsdf.closed_surface(), m.transmissive) << m.name;  // the glass sphere only
  }
  EXPECT_TRUE(fig1.material(fig1.objects()[7].material).bsdf.closed_surface());

  auto glass = [] {
    Material m;
    m.add(make_dielectric(0.2f, 1.5f));
    return m;
  };
  Scene s;
  const int on_sphere = s.add_material("on-sphere", glass(), true);
  const int on_cube = s.add_material("on-cube", glass(), true);
  const int on_knot = s.add_material("on-knot", glass(), true);
  const int on_quad = s.add_material("on-quad", glass(), true);
  const int on_open_cube = s.add_material("on-open-cube", glass(), true);
  const int on_inward_cube = s.add_material("on-inward-cube", glass(), true);
  const int shared = s.add_material("shared", glass(), true);
  const int opaque = s.add_material("opaque", glass(), false);
  s.add_sphere("sphere", {0, 0, 0}, 1, on_sphere);
  s.add_mesh("cube", cube({3, 0, 0}), on_cube);
  s.add_mesh("knot", make_torus_knot(2, 3, 2.0f, 0.8f, 0.45f, 60, 8), on_knot);
  s.add_mesh("quad", make_quad({0, 6, 0}, 1, 1), on_quad);
  s.add_mesh("open-cube", cube({6, 0, 0}, false, 5), on_open_cube);
  s.add_mesh("inward-cube", cube({9, 0, 0}, true), on_inward_cube);
  s.add_sphere("shared-sphere", {0, 9, 0}, 1, shared);
  s.add_mesh("shared-quad", make_quad({0, 12, 0}, 1, 1), shared);
  s.add_sphere("opaque-sphere", {0, 15, 0}, 1, opaque);
  s.set_environment(test_sky());
  const auto& o = s.objects();
  EXPECT_TRUE(o[0].closed && o[1].closed && o[2].closed);
  EXPECT_FALSE(o[3].closed || o[4].closed || o[5].closed);
  s.commit();
  EXPECT_TRUE(s.material(on_sphere).bsdf.closed_surface());
  EXPECT_TRUE(s.material(on_cube).bsdf.closed_surface());
  EXPECT_TRUE(s.material(on_knot).bsdf.closed_surface());
  EXPECT_FALSE(s.material(on_quad).bsdf.closed_surface());
  EXPECT_FALSE(s.material(on_open_cube).bsdf.closed_surface());
  EXPECT_FALSE(s.material(on_inward_cube).bsdf.closed_surface());
  EXPECT_FALSE(s.material(shared).bsdf.closed_surface());
  EXPECT_FALSE(s.material(opaque).bsdf.closed_surface());  // two-sided: no inside to leave out

  Scene off;
  off.set_proxy_closed_surfaces(false);
  const int g = off.add_material("glass", glass(), true);
  off.add_sphere("sphere", {0, 0, 0}, 1, g);
  off.set_environment(test_sky());
  off.commit();
  EXPECT_FALSE(off.material(g).bsdf.closed_surface());
}

// At a point on the outside of the fig1 glass sphere, product light samples go into the sphere
// (where the sphere always blocks them) only through cells that straddle the horizon; without the
// closed-surface proxy they follow the refraction lobe's ~90% of the proxy weight.
TEST(ClosedSurfaces, ProductLightSamplesOfTheGlassSphereStayOutside) {
  const Scene& scene = small_fig1();
  const Material& glass = scene.material(scene.objects()[7].material).bsdf;
  ASSERT_TRUE(glass.closed_surface());
  Material open_glass = glass;
  open_glass.set_closed_surface(false);
  const StrategyTables t = StrategyTables::build(*test_sky(), Strategy::Product);
  for (const Material* m : std::array<const Material*, 2>{&glass, &open_glass}) {
    LightSampler ls(t);
    const Frame frame(normalize(Vec3{0.2f, -1.0f, 0.3f}));
    ShadingContext sc;
    sc.n = frame.n;
    sc.wo = normalize(Vec3{0.0f, -1.0f, 0.1f});
    sc.wo_local = frame.to_local(sc.wo);
    sc.frame = &frame;
    sc.bsdf = m;
    ls.prepare(sc);
    PixelSampler rng(SamplerKind::Independent, 3, 4, 5);
    int inside = 0, valid = 0;
    for (int i = 0; i < 4000; ++i) {
      const DirectionSample d = ls.sample(rng.next2d());
      if (!(d.pdf > 0)) continue;
      ++valid;
      inside += dot(d.direction, frame.n) < 0;
    }
    ASSERT_GT(valid, 3900);
    const double share = double(inside) / valid;
    std::printf("%s glass: %.3f of the light samples go inside\n", m == &glass ? "closed" : "open", share);
    if (m == &glass)
      EXPECT_LT(share, 0.15);
    else
      EXPECT_GT(share, 0.5);
  }
}

// ---------------------------------------------------------------------------------------------
// The command's validation (one-line error, exit status 1).

using test::TempDir;

TEST(Command, RejectsBadOptionsWithOneLineErrors) {
  if (!fs::exists(test::envpis_binary())) GTEST_SKIP() << "envpis not built";
  TempDir dir;
  const std::string out = (dir.path / "o.exr").string();
  const std::vector<std::pair<std::string, std::string>> cases{
      {"--strategy nope --out " + out, "unknown strategy"},
      {"--scene nope --spp 1 --out " + out, "unknown scene"},
      {"--spp 0 --out " + out, "--spp"},
      {"--spp abc --out " + out, "--spp"},
      {"--width -3 --out " + out, "--width"},
      {"--height 100000 --out " + out, "--height"},
      {"--threads -1 --out " + out, "--threads"},
      {"--integrator bidir --out " + out, "unknown integrator"},
      {"--heuristic max --out " + out, "unknown MIS heuristic"},
      {"--sampler pmj --out " + out, "--sampler: unknown sampler 'pmj'"},
      {"--peak-ratio 0.5 --out " + out, "--peak-ratio: must be 0 (off) or in [1, 1e6]"},
      {"--peak-ratio nan --out " + out, "--peak-ratio"},
      {"--env-floor 2 --out " + out, "--env-floor"},
      {"--out /nonexistent-dir/x.exr", "cannot write"},
      {"--out " + (dir.path / "x.png").string(), "OpenEXR"},
      {"", "--out is required"},
      {"--env /nonexistent.exr --out " + out, "nonexistent.exr"},
      {"--env-orientation legacy --out " + out, "--env-orientation needs --env"},
      {"--env-filter nearest --out " + out, "--env-filter needs --env"},
      {"--env x.exr --env-orientation mirrored --out " + out, "--env-orientation: unknown lat-long orientation"},
      {"--env x.exr --env-filter cubic --out " + out, "--env-filter: unknown map filter 'cubic'"},
      {"--clamp-direct -0.5 --out " + out, "--clamp-direct: must be >= 0 (0: off), got '-0.5'"},
      {"--clamp-indirect nan --out " + out, "--clamp-indirect: expected a finite number, got 'nan'"},
      {"--filter-glossy -1 --out " + out, "--filter-glossy: must be >= 0 (0: off), got '-1'"},
      {"--caustics glass --out " + out, "--caustics: unknown caustics 'glass'"},
      {"--product-max-roughness 2 --out " + out, "--product-max-roughness: must be in [0, 1] or inf, got '2'"},
      {"--product-max-roughness glossy --out " + out, "--product-max-roughness: expected a finite number, got 'glossy'"},
      {"--product-max-roughness -0.1 --out " + out, "--product-max-roughness: must be in [0, 1] or inf"},
  };
  std::vector<std::pair<std::string, std::string>> render_cases;
  for (const auto& [args, expect] : cases) render_cases.emplace_back("render " + args, expect);
  test::expect_one_line_errors(render_cases);
  // And a tiny successful render.
  const test::CmdResult ok =
      test::run_envpis("render --scene fig1 --width 48 --height 8 --spp 2 --strategy product --out " + out);
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("samples/s"), std::string::npos);
  EXPECT_TRUE(fs::exists(out));
}

}  // namespace
}  // namespace envpis::render
