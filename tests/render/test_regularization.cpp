// SPDX-License-Identifier: Apache-2.0
// Path regularization (render/regularization.h), Cycles' clamp, caustics switches and filter glossy:
//   - off (the default) changes nothing, bit for bit; a switch with nothing to act on neither;
//   - the clamp bounds every sample: each contribution's channel mean is at most X, so a sample of a
//     path with D vertices is at most (2 D + 1) X, and the indirect clamp leaves one-bounce paths alone;
//   - caustics off removes exactly the light that reaches a diffuse floor through (or off) a sphere:
//     under a constant unit sky the floor is then rho (1 - (r / d)^2 cos beta), the sky the sphere
//     does not hide (the form factor of a sphere seen from a plane);
//   - filter glossy widens the lobes (eval, pdf, sample and the proxy all the widened lobe) and every
//     strategy still converges to the same image under it (z-test against a reference, Bonferroni).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <tuple>

#include "render/integrator.h"
#include "render/render.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

/// |z| threshold for a two-sided family-wise level 1e-3 over `tests` tests (Bonferroni).
double bonferroni_z(int tests) {
  const double alpha = 1e-3 / tests;
  double lo = 0, hi = 10;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  return lo;
}

std::shared_ptr<const EnvironmentMap> sunny_sky() {
  static const auto env = [] {
    SkyOptions o;
    o.width = 128;
    o.height = 64;
    o.sun_elevation = 35.0f;
    o.sun_azimuth = 250.0f;
    o.sun_radius = 6.0f;
    o.sun_radiance = 25.0f;
    return std::make_shared<const EnvironmentMap>(make_procedural_sky(o));
  }();
  return env;
}

Material one_lobe(std::shared_ptr<const Lobe> lobe) {
  Material m;
  m.add(std::move(lobe));
  return m;
}

/// A diffuse floor (albedo rho) with a sphere of `sphere` material above it, radius r at height h,
/// seen from straight above by an orthographic camera.
constexpr float kRho = 0.5f, kR = 1.0f, kH = 1.5f, kFilm = 6.0f;
Scene floor_and_sphere(Material sphere, bool transmissive, std::shared_ptr<const EnvironmentMap> env) {
  Scene s;
  const int floor = s.add_material("floor", one_lobe(make_lambert({kRho, kRho, kRho})), false);
  const int ball = s.add_material("ball", std::move(sphere), transmissive);
  s.add_mesh("floor", make_quad({0, 0, 0}, 4, 4), floor);
  s.add_sphere("ball", {0, 0, kH}, kR, ball);
  CameraSpec cam;
  cam.from = {0, 0, 10};
  cam.to = {0, 0, 0};
  cam.up = {0, 1, 0};
  cam.projection = Projection::Orthographic;
  cam.ortho_height = kFilm;
  cam.width = cam.height = 64;
  s.set_camera(cam);
  s.set_environment(std::move(env));
  s.commit();
  return s;
}

std::shared_ptr<const EnvironmentMap> unit_sky() {
  static const auto env = std::make_shared<const EnvironmentMap>(make_constant_environment({1, 1, 1}));
  return env;
}

RenderOptions path_options(Strategy s, int spp, std::uint64_t seed) {
  RenderOptions o;
  o.strategy = s;
  o.integrator = IntegratorKind::Path;
  o.spp = spp;
  o.seed = seed;
  o.oracle.resolution = 16;
  return o;
}

/// The floor's mean over the pixels far enough from the sphere's silhouette that no pixel mixes the
/// two, and the mean of the caustics-off answer rho (1 - (r / d)^2 cos beta) over the same pixels.
struct FloorMean {
  double mean = 0, variance = 0, expected = 0;
  std::size_t pixels = 0;
};
FloorMean floor_mean(const RenderResult& r) {
  FloorMean f;
  const double pixel = kFilm / r.height;
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * r.width + x;
      const double fx = (x + 0.5) * pixel - 0.5 * kFilm, fy = (y + 0.5) * pixel - 0.5 * kFilm;
      const double s = std::hypot(fx, fy);  // the answer is symmetric about the sphere's axis
      if (r.object_id[p] != 0 || s < kR + 2 * pixel) continue;
      const double d2 = s * s + kH * kH, cos_beta = kH / std::sqrt(d2);
      f.expected += kRho * (1 - kR * kR / d2 * cos_beta);
      f.mean += (double(r.rgb[p * 3]) + r.rgb[p * 3 + 1] + r.rgb[p * 3 + 2]) / 3;
      f.variance += r.variance[p];
      ++f.pixels;
    }
  f.mean /= double(f.pixels);
  f.expected /= double(f.pixels);
  f.variance /= double(f.pixels) * double(f.pixels);
  return f;
}

TEST(Regularization, ClampScalesTheContributionToChannelMeanX) {
  const Rgb c = clamp_contribution({3, 6, 9}, 2);  // sum 18 > 3 * 2: scaled by 6 / 18
  EXPECT_FLOAT_EQ(c.r, 1);
  EXPECT_FLOAT_EQ(c.g, 2);
  EXPECT_FLOAT_EQ(c.b, 3);
  const Rgb below = clamp_contribution({1, 2, 2.9f}, 2);  // sum 5.9 <= 6: unchanged
  EXPECT_EQ(below.b, 2.9f);
  EXPECT_EQ(clamp_contribution({100, 0, 0}, 0).r, 100.0f);  // 0 = off
  EXPECT_FLOAT_EQ(clamp_contribution({100, 0, 0}, 1).r, 3.0f);  // one channel may exceed X
}

TEST(Regularization, FilterGlossyRoughnessIsCycles) {
  EXPECT_FLOAT_EQ(filter_glossy_alpha(1.0f, 0.3f), 0.5f * std::sqrt(0.7f));
  EXPECT_FLOAT_EQ(filter_glossy_alpha(2.0f, 1.0f), 0.5f * std::sqrt(0.5f));
  EXPECT_EQ(filter_glossy_alpha(1.0f, 1.0f), 0.0f);   // p_min >= X: nothing
  EXPECT_EQ(filter_glossy_alpha(0.0f, 0.01f), 0.0f);  // off
  EXPECT_EQ(filter_glossy_alpha(1.0f, std::numeric_limits<float>::infinity()), 0.0f);  // the camera's vertex
}

TEST(Regularization, OptionsValidated) {
  RegularizationOptions o;
  EXPECT_FALSE(o.active());
  EXPECT_NO_THROW(validate(o));
  o.clamp_direct = -1;
  EXPECT_THROW(validate(o), Error);
  o.clamp_direct = std::nanf("");
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.filter_glossy = std::numeric_limits<float>::infinity();
  EXPECT_THROW(validate(o), Error);
  o = {};
  parse_caustics("none", &o);
  EXPECT_TRUE(o.active());
  EXPECT_EQ(caustics_string(o), "none");
  parse_caustics("refractive", &o);
  EXPECT_FALSE(o.caustics_reflective);
  EXPECT_TRUE(o.caustics_refractive);
  EXPECT_THROW(parse_caustics("glossy", &o), Error);
}

TEST(Regularization, OffOrWithNothingToActOnIsBitIdentical) {
  Material mirror = one_lobe(make_conductor_reflectance(0.05f, {0.9f, 0.9f, 0.9f}));
  const Scene scene = floor_and_sphere(mirror, false, sunny_sky());
  for (Strategy st : {Strategy::Mis, Strategy::Product}) {
    RenderOptions o = path_options(st, 8, 4);
    const RenderResult plain = render(scene, o);
    o.regularization.caustics_refractive = false;  // nothing refracts in this scene
    o.regularization.clamp_indirect = 1e-3f;       // one bounce only: every contribution is direct
    o.max_depth = 1;
    RenderOptions one = path_options(st, 8, 4);
    one.max_depth = 1;
    EXPECT_EQ(render(scene, one).rgb, render(scene, o).rgb) << to_string(st);
    RenderOptions again = path_options(st, 8, 4);
    again.regularization = RegularizationOptions{};
    EXPECT_EQ(plain.rgb, render(scene, again).rgb) << to_string(st);
    // And the caustics switch alone, on the whole path: the mirror still reflects.
    again.regularization.caustics_refractive = false;
    EXPECT_EQ(plain.rgb, render(scene, again).rgb) << to_string(st);
  }
}

TEST(Regularization, ClampBoundsEverySample) {
  const Scene scene = make_builtin_scene("fig1", sunny_sky());
  const float X = 0.05f;
  for (int depth : {1, 4}) {
    IntegratorOptions io;
    io.max_depth = depth;
    io.regularization.clamp_direct = X;
    io.regularization.clamp_indirect = X;
    IntegratorOptions plain = io;
    plain.regularization = {};
    for (Strategy st : {Strategy::Mis, Strategy::Product}) {
      const StrategyTables tables = StrategyTables::build(scene.environment(), st);
      LightSampler light(tables);
      const Camera camera(scene.camera(), 96, 16);
      const Integrator clamped(scene, io), unclamped(scene, plain);
      const double bound = (2 * depth + 1) * double(X) * (1 + 1e-5);  // 2 per vertex, + the sky
      double max_clamped = 0, max_plain = 0;
      for (int pix = 0; pix < 96 * 16; ++pix)
        for (int s = 0; s < 8; ++s)
          for (const Integrator* integrator : {&clamped, &unclamped}) {
            PixelSampler rng(SamplerKind::Sobol, 1, pix, s);
            const Point2 j = rng.next2d();
            const Ray ray = camera.generate_ray(float(pix % 96) + j.x, float(pix / 96) + j.y);
            const double v = integrator->li(ray, rng, light).average();
            double& max = integrator == &clamped ? max_clamped : max_plain;
            max = std::max(max, v);
          }
      EXPECT_LE(max_clamped, bound) << to_string(st) << " depth " << depth;
      EXPECT_GT(max_plain, 2 * bound) << "the test cannot fail: no sample above the bound without the clamp";
    }
  }
}

TEST(Regularization, CausticsOffRemovesTheLightThroughAndOffTheSphere) {
  Material glass = one_lobe(make_dielectric(0.01f, 1.5f));
  Material mirror = one_lobe(make_conductor_reflectance(0.001f, {1, 1, 1}));
  struct Case {
    const char* name;
    const Material* ball;
    bool transmissive;
    const char* caustics;
  };
  const Case cases[] = {{"glass, caustics none", &glass, true, "none"},
                        {"mirror, reflective caustics off", &mirror, false, "refractive"}};
  const double z_max = bonferroni_z(2);
  for (const Case& c : cases) {
    const Scene scene = floor_and_sphere(*c.ball, c.transmissive, unit_sky());
    RenderOptions o = path_options(Strategy::Mis, 64, 7);
    const FloorMean on = floor_mean(render(scene, o));
    parse_caustics(c.caustics, &o.regularization);
    const FloorMean off = floor_mean(render(scene, o));
    const double z = (off.mean - off.expected) / std::sqrt(off.variance);
    std::printf("%s: floor %.5f, expected %.5f (z %+.2f); with caustics %.5f\n", c.name, off.mean, off.expected, z,
                on.mean);
    EXPECT_GT(off.pixels, 1000u);
    EXPECT_LT(std::fabs(z), z_max) << c.name;
    // With the caustic the floor is brighter by about rho times the sky the sphere hides.
    EXPECT_GT((on.mean - off.mean) / std::sqrt(on.variance + off.variance), 20.0) << c.name;
  }
}

TEST(Regularization, FilterGlossyWidensWhatIsSampledEvaluatedAndProxied) {
  const Vec3 wo = normalize(Vec3{0.3f, -0.2f, 0.9f});
  LobeFilter f;
  f.min_alpha = 0.3f;
  for (auto [name, narrow, wide] :
       {std::tuple{"conductor", make_conductor_reflectance(0.05f, {0.9f, 0.8f, 0.7f}),
                   make_conductor_reflectance(0.3f, {0.9f, 0.8f, 0.7f})},
        std::tuple{"dielectric", make_dielectric(0.05f, 1.5f), make_dielectric(0.3f, 1.5f)}}) {
    Material m = one_lobe(narrow), w = one_lobe(wide), filtered;
    m.filter_into(f, &filtered);
    for (int i = 0; i < 64; ++i) {
      const float u = (i + 0.5f) / 64;
      const auto s = filtered.sample(wo, {u, std::fmod(u * 7.31f, 1.0f)}, std::fmod(u * 3.7f, 1.0f));
      if (!s) continue;
      EXPECT_NEAR(s->pdf, filtered.pdf(wo, s->wi), 1e-4f * s->pdf) << name;  // sampled = evaluated density
      EXPECT_NEAR(filtered.pdf(wo, s->wi), w.pdf(wo, s->wi), 1e-3f * s->pdf) << name;  // = the alpha-0.3 lobe's
      EXPECT_NEAR(filtered.eval(wo, s->wi).g, w.eval(wo, s->wi).g, 1e-3f * w.eval(wo, s->wi).g + 1e-6f) << name;
    }
    BsdfProxy p;
    filtered.fill_proxy(p, wo);
    EXPECT_FLOAT_EQ(p.alpha_reflection, 0.3f) << name;  // the product strategy's proxy sees the wide lobe
    // A lobe already rougher than the floor is left as it is (shared, not copied).
    f.min_alpha = 0.01f;
    m.filter_into(f, &filtered);
    EXPECT_EQ(filtered.pdf(wo, normalize(Vec3{-0.3f, 0.2f, 0.9f})), m.pdf(wo, normalize(Vec3{-0.3f, 0.2f, 0.9f})));
    f.min_alpha = 0.3f;
  }
}

/// A diffuse floor with a glossy and a glass sphere: with filter glossy, the spheres the floor sees
/// (and the floor the spheres see) are widened.
Scene glossy_scene() {
  Scene s;
  const int floor = s.add_material("floor", one_lobe(make_lambert({0.6f, 0.6f, 0.6f})), false);
  const int metal = s.add_material("metal", one_lobe(make_conductor_reflectance(0.03f, {0.9f, 0.7f, 0.4f})), false);
  const int glass = s.add_material("glass", one_lobe(make_dielectric(0.02f, 1.5f)), true);
  s.add_mesh("floor", make_quad({0, 0, 0}, 6, 6), floor);
  s.add_sphere("metal", {-1.2f, 0, 1}, 1, metal);
  s.add_sphere("glass", {1.2f, 0, 1}, 1, glass);
  s.set_camera(look_at({0, -7, 3.5f}, {0, 0, 0.7f}, 40, 48, 24));
  s.set_environment(sunny_sky());
  s.commit();
  return s;
}

TEST(Regularization, FilterGlossyEveryStrategyConvergesToTheSameImage) {
  const Scene scene = glossy_scene();
  const int objects = 3;
  auto options = [](Strategy st, int spp, std::uint64_t seed) {
    RenderOptions o = path_options(st, spp, seed);
    o.max_depth = 4;
    o.regularization.filter_glossy = 1.0f;
    return o;
  };
  const RenderResult ref = render(scene, options(Strategy::Mis, 1024, 1000));
  const RenderResult ref_product = render(scene, options(Strategy::Product, 1024, 2000));
  const auto m_ref = object_means(ref, objects), m_ref_product = object_means(ref_product, objects);
  const double z_max = bonferroni_z(static_cast<int>(all_strategies().size()) * objects + objects);
  for (int i = 0; i < objects; ++i) {  // the two references agree
    const double z = (m_ref[i].mean - m_ref_product[i].mean) / std::sqrt(m_ref[i].variance + m_ref_product[i].variance);
    EXPECT_LT(std::fabs(z), z_max) << "references disagree on " << scene.objects()[i].name;
  }
  // The filter changes the image (the caustics the floor receives are blurred, and rough GGX loses more).
  RenderOptions plain = options(Strategy::Mis, 1024, 1000);
  plain.regularization = {};
  const auto m_plain = object_means(render(scene, plain), objects);
  double z_change = 0;
  for (int i = 0; i < objects; ++i)
    z_change = std::max(z_change, std::fabs(m_plain[i].mean - m_ref[i].mean) /
                                      std::sqrt(m_plain[i].variance + m_ref[i].variance));
  EXPECT_GT(z_change, 5.0) << "filter glossy changed no object's mean";
  for (Strategy st : all_strategies()) {
    const int spp = st == Strategy::Oracle ? 32 : (st == Strategy::Env ? 1024 : 128);
    const RenderResult r = render(scene, options(st, spp, 42));
    ASSERT_EQ(r.nonfinite_pixels, 0u) << to_string(st);
    const auto m = object_means(r, objects);
    const auto& against = st == Strategy::Mis ? m_ref_product : m_ref;
    std::printf("%-9s", to_string(st));
    for (int i = 0; i < objects; ++i) {
      const double z = (m[i].mean - against[i].mean) / std::sqrt(m[i].variance + against[i].variance);
      std::printf("  %s %.4f (z %+.2f)", scene.objects()[i].name.c_str(), m[i].mean, z);
      EXPECT_LT(std::fabs(z), z_max) << to_string(st) << " on " << scene.objects()[i].name;
    }
    std::printf("\n");
  }
}

}  // namespace
}  // namespace envpis::render
