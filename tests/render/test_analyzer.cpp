// SPDX-License-Identifier: Apache-2.0
// Tests of the exact variance analyzer (render/analyzer.h) and `envpis analyze`:
//   - its variance agrees with the sample variance of the renderer's own one-sample direct estimates
//     (Integrator::li with the strategies' LightSamplers), within a confidence interval built from the
//     sample fourth moment, and its mean with the estimates' mean;
//   - cases with a known answer: BSDF sampling of a Lambert sphere under a constant sky has variance 0,
//     and so does the exact product limit for a grey integrand;
//   - the quadrature converges: refining further changes no V by more than 1%;
//   - clean errors for bad options (library and command).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli_util.h"
#include "render/analyzer.h"
#include "render_test_scenes.h"
#include "render/camera.h"
#include "render/integrator.h"
#include "render/sampler.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

using envpis::test::single;
using envpis::test::sphere_scene;

/// A smooth coloured sky: a broad warm lobe (a soft sun, 40x the dimmest sky) over a blue gradient.
/// Every strategy's weights f / p stay bounded on it, so sample variances have finite fourth moments.
std::shared_ptr<const EnvironmentMap> smooth_sky() {
  static const auto env = [] {
    const int w = 128, h = 64;
    std::vector<float> px(static_cast<std::size_t>(w) * h * 3);
    const Vec3 sun = normalize(Vec3{0.4f, 0.5f, 0.6f});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Vec3 d = latlong_to_direction({(float(x) + 0.5f) / w, (float(y) + 0.5f) / h});
        const float s = 8.0f * std::exp(6.0f * (dot(d, sun) - 1.0f));
        const float sky = 0.2f + 0.15f * std::max(d.z, 0.0f);
        float* p = &px[(static_cast<std::size_t>(y) * w + x) * 3];
        p[0] = sky * 0.7f + s;
        p[1] = sky * 0.85f + 0.8f * s;
        p[2] = sky * 1.2f + 0.5f * s;
      }
    return std::make_shared<const EnvironmentMap>(EnvironmentMap::from_pixels(w, h, std::move(px)));
  }();
  return env;
}

AnalyzerOptions options_for(std::vector<Strategy> strategies) {
  AnalyzerOptions o;
  o.strategies = std::move(strategies);
  o.oracle.resolution = 16;
  return o;
}

struct MonteCarlo {
  double v = 0, v_stderr = 0;  // channel mean of s^2 / I^2 and its standard error
  double max_mean_z = 0;       // largest |mean - I| / stderr over the channels
};

/// N one-sample direct estimates of the radiance along `ray` by the renderer (Integrator::li with
/// independent random numbers), against the analyzer's per-channel integrals I.
MonteCarlo monte_carlo(const Scene& scene, Strategy strategy, const AnalyzerOptions& o, const Ray& ray,
                       const double I[3], int n, std::uint64_t seed) {
  const StrategyTables tables = StrategyTables::build(scene.environment(), strategy, o.oracle, o.product, o.light_table);
  LightSampler light(tables);
  IntegratorOptions io;
  io.kind = IntegratorKind::Direct;
  io.heuristic = o.heuristic;
  const Integrator integrator(scene, io);
  double m1[3] = {0, 0, 0}, m2[3] = {0, 0, 0};
  std::vector<Rgb> values(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    PixelSampler rng(SamplerKind::Independent, seed, 0, static_cast<std::uint64_t>(i));
    values[i] = integrator.li(ray, rng, light);
    const double c[3] = {values[i].r, values[i].g, values[i].b};
    for (int k = 0; k < 3; ++k) m1[k] += c[k];
  }
  for (int k = 0; k < 3; ++k) m1[k] /= n;
  double m4[3] = {0, 0, 0};
  for (const Rgb& v : values) {
    const double c[3] = {v.r, v.g, v.b};
    for (int k = 0; k < 3; ++k) {
      const double d2 = (c[k] - m1[k]) * (c[k] - m1[k]);
      m2[k] += d2;
      m4[k] += d2 * d2;
    }
  }
  MonteCarlo r;
  for (int k = 0; k < 3; ++k) {
    const double var = m2[k] / (n - 1), mu4 = m4[k] / n;
    const double var_stderr = std::sqrt(std::max(0.0, mu4 - var * var) / n);  // of the variance estimate
    r.v += var / (I[k] * I[k]) / 3;
    r.v_stderr += var_stderr / (I[k] * I[k]) / 3;  // channels may correlate: add standard errors
    r.max_mean_z = std::max(r.max_mean_z, std::fabs(m1[k] - I[k]) / std::sqrt(var / n + 1e-300));
  }
  return r;
}

// The heart of the matter: the analyzer's V is the variance the renderer's estimator has. 3 points x
// 5 strategies x 2 materials = 30 comparisons; |z| < 4 for each (the quadrature's own 1% is added to
// the interval).
TEST(Analyzer, AgreesWithTheRenderersSampleVariance) {
  const std::vector<Strategy> strategies{Strategy::Bsdf, Strategy::Env, Strategy::Mis, Strategy::MisComp,
                                         Strategy::Product};
  struct Case {
    const char* name;
    Material m;
  };
  const Case cases[] = {{"ggx-0.3", single(make_conductor_reflectance(0.3f, {0.9f, 0.8f, 0.7f}))},
                        {"lambert", single(make_lambert({0.8f, 0.8f, 0.8f}))}};
  for (const Case& c : cases) {
    const Scene scene = sphere_scene(c.m, false, smooth_sky());
    const AnalyzerOptions o = options_for(strategies);
    const Analyzer analyzer(scene, o);
    const std::vector<ShadingPointRef> points = first_hit_points(scene, 3);
    ASSERT_EQ(points.size(), 3u);
    for (std::size_t p = 0; p < points.size(); ++p) {
      const auto a = analyzer.analyze(points[p].ray);
      ASSERT_TRUE(a.has_value());
      for (std::size_t s = 0; s < strategies.size(); ++s) {
        SCOPED_TRACE(std::string(c.name) + " point " + std::to_string(p) + " " + to_string(strategies[s]));
        EXPECT_LT(std::fabs(a->bias[s]), 1e-4);
        const MonteCarlo mc = monte_carlo(scene, strategies[s], o, points[p].ray, a->integral, 200000, 17 + p);
        const double tolerance = std::hypot(mc.v_stderr, 0.01 * a->v[s]);
        EXPECT_LT(std::fabs(mc.v - a->v[s]), 4 * tolerance)
            << "analyzer " << a->v[s] << ", Monte Carlo " << mc.v << " +- " << mc.v_stderr;
        EXPECT_LT(mc.max_mean_z, 4.5);
      }
    }
  }
}

// BSDF sampling of a Lambert surface is proportional to f under a constant sky: variance 0. The exact
// product limit is 0 for any grey integrand, and exact-T limits lie between it and environment sampling.
TEST(Analyzer, KnownZeroVariances) {
  // 256 x 128 texels: a 372 x 372 quadrature grid, fine enough for the horizon's texels.
  const auto white = std::make_shared<const EnvironmentMap>(make_constant_environment({1, 1, 1}, 256, 128));
  const Scene scene = sphere_scene(single(make_lambert({0.5f, 0.5f, 0.5f})), false, white);
  AnalyzerOptions o = options_for({Strategy::Bsdf, Strategy::Env, Strategy::Mis});
  const Analyzer analyzer(scene, o);
  for (const ShadingPointRef& p : first_hit_points(scene, 4)) {
    const auto a = analyzer.analyze(p.ray);
    ASSERT_TRUE(a.has_value());
    EXPECT_NEAR(a->integral[0], 0.5, 2e-3);  // white furnace: albedo times radiance
    EXPECT_LT(a->v[0], 1e-4);                // bsdf
    EXPECT_NEAR(a->v_light[1], 5.0 / 3.0, 0.02) << "uniform sampling of a cosine over the sphere: 8/3 - 1";
    EXPECT_LT(a->v_product, 1e-9);
    EXPECT_GE(a->v_product, 0.0) << "a variance: round-off below 0 made the object's geometric mean NaN";
    for (double v : a->v_exact) {
      EXPECT_GT(v, a->v_product - 1e-9);
      EXPECT_LE(v, a->v_light[1] * 1.001);
    }
  }
  // Per object, a limit of 0 at every point is 0 (the geometric mean leaves zeros out: it was NaN).
  const SceneAnalysis all = analyze_scene(analyzer, scene, 4, 0);
  ASSERT_FALSE(all.objects.empty());
  for (const ObjectAnalysis& r : all.objects) {
    EXPECT_TRUE(std::isfinite(r.v_product));
    EXPECT_GE(r.v_product, 0.0);
    EXPECT_LT(r.v_product, 1e-9);
  }
}

// Refining the quadrature further (8 x 8 points per refined texel, a quarter of the share and a tenth
// of the error tolerance) changes no V by more than 1% (+ 1e-4: a relative variance of 0.008, as
// BSDF sampling has on a sharp lobe, needs its integrals to 1e-4 for 1%), on a real map with a small
// bright sun and the sharpest lobe of fig1.
TEST(Analyzer, QuadratureConverges) {
  const std::string path = std::string(kBlenderWorldDir) + "/sunrise.exr";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "blender-data maps not installed";
  const auto env = std::make_shared<const EnvironmentMap>(EnvironmentMap::load(path));
  for (float alpha : {0.02f, 0.3f}) {
    SCOPED_TRACE("alpha " + std::to_string(alpha));
    const Scene scene = sphere_scene(single(make_conductor_reflectance(alpha, {0.9f, 0.9f, 0.9f})), false, env);
    AnalyzerOptions coarse = options_for({Strategy::Bsdf, Strategy::Env, Strategy::Mis, Strategy::Product});
    AnalyzerOptions fine = coarse;
    fine.refine = 8;
    fine.refine_share = coarse.refine_share / 4;
    fine.refine_tolerance = coarse.refine_tolerance / 10;
    const Analyzer a(scene, coarse), b(scene, fine);
    for (const ShadingPointRef& p : first_hit_points(scene, 1)) {
      const auto x = a.analyze(p.ray), y = b.analyze(p.ray);
      ASSERT_TRUE(x && y);
      auto near = [](double u, double v) { return std::fabs(u - v) <= 0.01 * std::fabs(v) + 1e-4; };
      for (std::size_t s = 0; s < coarse.strategies.size(); ++s) {
        EXPECT_PRED2(near, x->v[s], y->v[s]) << to_string(coarse.strategies[s]);
        if (std::isfinite(y->v_light[s])) EXPECT_PRED2(near, x->v_light[s], y->v_light[s]);
      }
      for (std::size_t l = 0; l < coarse.exact_levels.size(); ++l) EXPECT_PRED2(near, x->v_exact[l], y->v_exact[l]);
      EXPECT_PRED2(near, x->v_product, y->v_product);
      EXPECT_GT(y->evaluations, x->evaluations);
    }
  }
}

// The coarser exact levels are summed from the finest level they divide: each level's V must be the
// one it has when it is analyzed alone, point by point (levels that divide each other and ones that do
// not, on a grid whose texels straddle the cells' edges).
TEST(Analyzer, ExactLevelsFromFinerLevelsEqualThemAlone) {
  const Scene scene = sphere_scene(single(make_conductor_reflectance(0.1f, {0.9f, 0.9f, 0.9f})), false, smooth_sky());
  AnalyzerOptions together = options_for({Strategy::Mis});
  together.exact_levels = {5, 7, 10, 30};
  const Analyzer all(scene, together);
  for (std::size_t l = 0; l < together.exact_levels.size(); ++l) {
    AnalyzerOptions alone = together;
    alone.exact_levels = {together.exact_levels[l]};
    const Analyzer one(scene, alone);
    ASSERT_NE(one.grid_resolution() % 30, 0) << "the texels should straddle some cells' edges";
    for (const ShadingPointRef& p : first_hit_points(scene, 2)) {
      const auto x = all.analyze(p.ray), y = one.analyze(p.ray);
      ASSERT_TRUE(x && y);
      EXPECT_NEAR(x->v_exact[l], y->v_exact[0], 1e-9 * std::fabs(y->v_exact[0])) << "level " << alone.exact_levels[0];
    }
  }
}

// Tracing the quadrature directions changes nothing for a sphere alone (it only hides its own lower
// hemisphere, which no direction reaches anyway), and lowers I when another sphere blocks part of
// the sky.
TEST(Analyzer, Visibility) {
  const Scene lone = sphere_scene(single(make_lambert({0.8f, 0.8f, 0.8f})), false, smooth_sky());
  AnalyzerOptions o = options_for({Strategy::Mis, Strategy::Product});
  AnalyzerOptions traced = o;
  traced.visibility = true;
  for (const ShadingPointRef& p : first_hit_points(lone, 2)) {
    const auto a = Analyzer(lone, o).analyze(p.ray), b = Analyzer(lone, traced).analyze(p.ray);
    ASSERT_TRUE(a && b);
    EXPECT_NEAR(b->integral[0], a->integral[0], 1e-3 * a->integral[0]);
    EXPECT_NEAR(b->v[1], a->v[1], 1e-2 * a->v[1]);
  }
  Scene blocked;
  blocked.add_material("m", single(make_lambert({0.8f, 0.8f, 0.8f})), false);
  blocked.add_sphere("sphere", {0, 0, 0}, 1.0f, 0);
  blocked.add_sphere("blocker", {0, 0, 2.5f}, 1.0f, 0);  // above: hides part of the sky of the top half
  const CameraSpec cam = lone.camera();
  blocked.set_camera(cam);
  blocked.set_environment(smooth_sky());
  blocked.commit();
  const Camera camera(cam, cam.width, cam.height);
  const Ray ray = camera.generate_ray(0.5f * cam.width, 0.3f * cam.height);  // the sphere's upper part
  const auto a = Analyzer(blocked, o).analyze(ray), b = Analyzer(blocked, traced).analyze(ray);
  ASSERT_TRUE(a && b);
  EXPECT_LT(b->integral[0], 0.95 * a->integral[0]);
  for (double bias : b->bias) EXPECT_LT(std::fabs(bias), 1e-4);
}

TEST(Analyzer, RejectsBadOptions) {
  AnalyzerOptions o;
  o.refine = 0;
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.refine_share = 0;
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.refine_tolerance = 2;
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.exact_levels = {0};
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.strategies.clear();
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.exact_levels = {1000};  // finer than the small sky's table
  const Scene scene = sphere_scene(single(make_lambert({0.5f, 0.5f, 0.5f})), false, smooth_sky());
  EXPECT_THROW(Analyzer(scene, o), Error);
  EXPECT_THROW(first_hit_points(scene, 0), Error);
}

TEST(AnalyzeCommand, CleanErrors) {
  if (!std::filesystem::exists(test::envpis_binary())) GTEST_SKIP() << "envpis not built";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"--points 0", "--points: must be in 1..100000"},
      {"--strategies foo", "--strategies: unknown strategy 'foo'"},
      {"--strategies ,", "--strategies: expected a comma-separated list"},
      {"--refine 0", "--refine: must be in 1..64"},
      {"--refine-share 2", "--refine-share: must be in [1e-12, 1]"},
      {"--refine-tolerance 0", "--refine-tolerance: must be in [1e-12, 1]"},
      {"--exact 12,x", "--exact: expected an integer"},
      {"--exact 0", "--exact: must be in 1..1024"},
      {"--json /nonexistent-dir/a.json", "cannot write --json"},
      {"--scene nope.json", "scene file 'nope.json' does not exist"},
  };
  std::vector<std::string> args;
  for (const auto& c : cases) args.push_back("analyze " + c.first);
  const auto results = test::run_envpis_all(args);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].first);
    EXPECT_EQ(results[i].code, 1) << results[i].output;
    EXPECT_NE(results[i].output.find("envpis analyze: error: " + cases[i].second), std::string::npos)
        << results[i].output;
  }
}

}  // namespace
}  // namespace envpis::render
