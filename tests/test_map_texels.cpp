// SPDX-License-Identifier: Apache-2.0
// The importance table with the lat-long map's own texels as its fine level (FineTexels::Map): its
// density is the map's (environment sampling), exact for the product sampler (chi-square per map
// texel, sample / pdf / invert agree, the samples' texture coordinates are the map's look-ups),
// bounded light-sample weights, clean errors.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "chi2.h"
#include "envpis/envpis.h"
#include "stress_maps.h"

namespace envpis {
namespace {

ImportanceTableOptions map_options(int subdivision = 1, float floor = 1e-4f, float k = 8.0f, bool compensated = false) {
  ImportanceTableOptions o;
  o.fine_texels = FineTexels::Map;
  o.subdivision = subdivision;
  o.floor = floor;
  o.peak_ratio = k;
  o.compensated = compensated;
  return o;
}

EnvironmentMap random_map(int w, int h, std::uint64_t seed, MapFilter filter = MapFilter::Nearest,
                          Mat3 rotation = {}) {
  std::mt19937_64 rng(seed);
  std::lognormal_distribution<float> L(0.0f, 1.5f);
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
  for (float& v : rgb) v = L(rng);
  EnvironmentMapOptions o;
  o.layout = MapLayout::LatLong;  // also 1 x 1
  o.filter = filter;
  o.rotation = rotation;
  return EnvironmentMap::from_pixels(w, h, std::move(rgb), o);
}

double texel_sr(int w, int h, int y) {
  return 2.0 * M_PI / w * (std::cos(M_PI * y / h) - std::cos(M_PI * (y + 1) / h));
}

// The chi-square test of any sampler over the map's texels.
template <class Sampler>
test::Chi2Result texel_chi2(const Sampler& s, const EnvironmentMap& map, int tests) {
  test::Chi2Options opt;
  opt.samples = 200000;
  opt.test_count = tests;
  const int w = map.width(), h = map.height();
  return test::texel_chi2(
      [&](float u1, float u2) -> std::optional<Vec3> {
        const DirectionSample d = s.sample({u1, u2});
        if (!(d.pdf > 0)) return std::nullopt;
        return d.direction;
      },
      [&](Vec3 d) { return double(s.pdf(d)); }, w, h,
      [&](Vec3 d) {
        const TexelCoord c = map.texel_coord(direction_to_latlong(map.to_map(d)));
        return static_cast<std::size_t>(c.y) * w + c.x;
      },
      [&](std::size_t t) {
        return map.to_world(latlong_to_direction({(float(t % w) + 0.5f) / w, (float(t / w) + 0.5f) / h}));
      },
      opt);
}

TEST(MapTexels, OptionsAndErrors) {
  EXPECT_EQ(parse_fine_texels("map"), FineTexels::Map);
  EXPECT_EQ(parse_fine_texels("equal-area"), FineTexels::EqualArea);
  EXPECT_EQ(parse_fine_texels("auto"), FineTexels::Auto);
  EXPECT_THROW(parse_fine_texels("latlong"), Error);
  EXPECT_STREQ(to_string(FineTexels::Map), "map");
  const EnvironmentMap latlong = random_map(16, 8, 1);
  std::vector<float> grey(16 * 16 * 3, 1.0f);
  const EnvironmentMap square = EnvironmentMap::from_pixels(16, 16, grey);  // Auto layout: equal-area
  EXPECT_THROW(ImportanceTable(square, map_options()), Error);
  ImportanceTableOptions o;
  o.fine_texels = FineTexels::Auto;
  EXPECT_EQ(ImportanceTable(latlong, o).fine_texels(), FineTexels::Map);  // nearest look-ups
  EXPECT_EQ(ImportanceTable(random_map(16, 8, 1, MapFilter::Bilinear), o).fine_texels(), FineTexels::EqualArea);
  EXPECT_EQ(ImportanceTable(square, o).fine_texels(), FineTexels::EqualArea);
  EXPECT_EQ(resolve_fine_texels(FineTexels::Auto, latlong), FineTexels::Map);
  EXPECT_EQ(resolve_fine_texels(FineTexels::Map, square), FineTexels::Map);  // an explicit choice stays
  const ImportanceTable t(latlong, map_options());
  EXPECT_EQ(t.fine_resolution(), 0);
  EXPECT_GT(t.bytes_used(), 0u);
}

// Without floor and peak bound, the environment's density is exactly the map's: average(texel) /
// integral, the integral being sum over texels of average x solid angle.
TEST(MapTexels, EnvironmentDensityIsTheMapsOwn) {
  for (int S : {1, 4}) {
    const EnvironmentMap map = random_map(40, 20, 3, MapFilter::Nearest, Mat3::rotate_z(37));
    const ImportanceTable t(map, map_options(S, 0, 0));
    double integral = 0;
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 40; ++x) integral += map.texel(x, y).average() * texel_sr(40, 20, y);
    EXPECT_NEAR(t.integral() / integral, 1.0, 1e-6);
    std::mt19937_64 rng(5);
    std::normal_distribution<float> N;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 d = normalize(Vec3{N(rng), N(rng), N(rng)});
      const double want = map.eval(d).average() / integral;
      ASSERT_NEAR(t.pdf(d) / want, 1.0, 2e-5) << "S " << S << " direction " << i;
    }
  }
}

struct Case {
  std::string name;
  EnvironmentMap map;
  ImportanceTableOptions options;
};

std::vector<Case> adversarial_cases() {
  std::vector<Case> cases;
  for (const char* name : {"seam", "north-pole", "south-pole", "cell-corner", "subtexel", "two-suns"})
    for (const test::StressMap& m : test::stress_family())
      if (m.name == name) {
        EnvironmentMapOptions nearest;
        nearest.filter = MapFilter::Nearest;
        cases.push_back({m.name + "/bilinear/S4", test::make_stress_map(m, 96, 48), map_options(4)});
        cases.push_back({m.name + "/nearest/S1", test::make_stress_map(m, 96, 48, nearest), map_options(1)});
      }
  cases.push_back({"1x1", random_map(1, 1, 7), map_options(4)});
  cases.push_back({"odd-7x3", random_map(7, 3, 8, MapFilter::Bilinear), map_options(2)});
  cases.push_back({"rotated-compensated", random_map(64, 32, 9, MapFilter::Bilinear, Mat3::rotate_z(20)),
                   map_options(4, 1e-4f, 8, true)});
  // No floor, compensated, every third texel black: most samples sit beside a texel of zero density,
  // so a direction that round-off moves across an edge would come back with pdf 0.
  std::vector<float> speckled(96 * 48 * 3);
  for (int t = 0; t < 96 * 48; ++t)
    for (int c = 0; c < 3; ++c) speckled[t * 3 + c] = (t % 96 * 7 + t / 96 * 13) % 3 == 0 ? 0.0f : 1.0f + 0.05f * float(t / 96);
  cases.push_back({"speckled-compensated", EnvironmentMap::from_pixels(96, 48, std::move(speckled)), map_options(4, 0.0f, 8, true)});
  std::vector<float> rgb(64 * 32 * 3, 0.01f);  // one texel 1e6 times brighter than the rest
  for (int c = 0; c < 3; ++c) rgb[(5 * 64 + 17) * 3 + c] = 1e4f;
  cases.push_back({"spike", EnvironmentMap::from_pixels(64, 32, std::move(rgb)), map_options(4)});
  return cases;
}

TEST(MapTexels, EnvironmentSamplingChiSquare) {
  const std::vector<Case> cases = adversarial_cases();
  for (const Case& c : cases) {
    const ImportanceTable t(c.map, c.options);
    ASSERT_FALSE(t.empty()) << c.name;
    const test::Chi2Result r = texel_chi2(t, c.map, static_cast<int>(cases.size()));
    EXPECT_TRUE(r.passed) << c.name << ": " << r.message;
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4) << c.name;
  }
}

struct Shading {
  std::string label;
  Vec3 n, wo;
  BsdfProxy proxy;
};

std::vector<Shading> shading_points() {
  std::vector<Shading> s;
  BsdfProxy glossy, diffuse, mixed, glass;
  glossy.add_reflection(1.0f, 0.05f);
  diffuse.add_diffuse(1.0f);
  mixed.add_diffuse(0.3f);
  mixed.add_reflection(0.7f, 0.3f);
  glass.add_reflection(0.1f, 0.02f);
  glass.add_refraction(0.9f, 0.02f, 1.5f);
  s.push_back({"glossy-up", {0, 0, 1}, normalize(Vec3{0.3f, 0.1f, 1}), glossy});
  s.push_back({"glossy-grazing", normalize(Vec3{1, 0.2f, 0.1f}), normalize(Vec3{0.1f, 1, 0.05f}), glossy});
  s.push_back({"diffuse-down", {0, 0, -1}, {0, 0, -1}, diffuse});
  s.push_back({"mixed", normalize(Vec3{0.2f, -0.7f, 0.4f}), normalize(Vec3{0.5f, -0.5f, 0.7f}), mixed});
  s.push_back({"glass", {0, 0, 1}, normalize(Vec3{0.4f, 0, 1}), glass});
  return s;
}

TEST(MapTexels, ProductSamplingChiSquare) {
  const std::vector<Case> cases = adversarial_cases();
  const std::vector<Shading> points = shading_points();
  const int tests = static_cast<int>(cases.size() * points.size() * 2);
  for (const Case& c : cases)
    for (bool refine : {false, true}) {
      if (refine && c.options.subdivision < 2) continue;
      const ImportanceTable t(c.map, c.options);
      ProductSamplerOptions po;
      po.refine = refine;
      ProductSampler ps(t, po);
      for (const Shading& p : points) {
        ASSERT_TRUE(ps.prepare(p.n, p.wo, p.proxy)) << c.name << " " << p.label;
        const test::Chi2Result r = texel_chi2(ps, c.map, tests);
        EXPECT_TRUE(r.passed) << c.name << " refine " << refine << " " << p.label << ": " << r.message;
        EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4) << c.name << " " << p.label;
      }
    }
}

// A sample's pdf is pdf() of its direction, and invert() finds a u that samples the same direction.
TEST(MapTexels, SamplePdfAndInvertAgree) {
  for (const Case& c : adversarial_cases()) {
    const ImportanceTable t(c.map, c.options);
    ProductSamplerOptions po;
    po.refine = c.options.subdivision > 1;
    ProductSampler ps(t, po);
    const Shading p = shading_points()[3];
    ASSERT_TRUE(ps.prepare(p.n, p.wo, p.proxy));
    const auto check = [&](const auto& sampler, const char* what) {
      std::mt19937_64 rng(11);
      std::uniform_real_distribution<float> U(0.0f, 1.0f);
      for (int i = 0; i < 4000; ++i) {
        const Point2 u{U(rng), U(rng)};
        const DirectionSample s = sampler.sample(u);
        ASSERT_GT(s.pdf, 0) << c.name << " " << what;
        ASSERT_NEAR(s.pdf / sampler.pdf(s.direction), 1.0f, 1e-4f) << c.name << " " << what << " u " << u.x << " " << u.y;
        const Vec3 d = sampler.sample(sampler.invert(s.direction)).direction;
        EXPECT_GT(dot(d, s.direction), 0.99999f) << c.name << " " << what << " u " << u.x << " " << u.y;
        // The sample's texture coordinate is where the map reads its direction, so the renderer's
        // radiance and pdf from it are eval's and pdf's exactly.
        const Point2 tex = c.map.texture_coord(s.direction);
        ASSERT_EQ(s.texture.x, tex.x) << c.name << " " << what;
        ASSERT_EQ(s.texture.y, tex.y) << c.name << " " << what;
        const Rgb a = c.map.eval_texture(s.texture), b = c.map.eval(s.direction);
        ASSERT_TRUE(a.r == b.r && a.g == b.g && a.b == b.b) << c.name << " " << what;
        ASSERT_EQ(sampler.pdf(s.direction, tex), sampler.pdf(s.direction)) << c.name << " " << what;
        // Any direction, not normalized: the pdf given its texture coordinate is its pdf.
        const Vec3 r{U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f};
        ASSERT_EQ(sampler.pdf(r * 3.0f, c.map.texture_coord(r * 3.0f)), sampler.pdf(r * 3.0f)) << c.name << " " << what;
      }
    };
    check(t, "environment");
    check(ps, "product");
  }
}

// The guarantee of importance_table.h: no light sample weighs more than K times the integral
// (bilinear look-ups, the peak bound over each texel's 3 x 3 neighbourhood); under nearest look-ups
// no more than the integral itself (the importance is the texel's own value, or the floor above it).
TEST(MapTexels, LightSampleWeightsAreBounded) {
  for (const Case& c : adversarial_cases()) {
    if (c.options.compensated) continue;
    const ImportanceTable t(c.map, c.options);
    const double bound = (c.map.filter() == MapFilter::Nearest ? 1.0 : c.options.peak_ratio) * t.integral();
    std::mt19937_64 rng(13);
    std::normal_distribution<float> N;
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    double worst = 0;
    for (int i = 0; i < 100000; ++i) {
      const Vec3 a = normalize(Vec3{N(rng), N(rng), N(rng)});
      const Vec3 b = t.sample({U(rng), U(rng)}).direction;
      for (Vec3 d : {a, b}) worst = std::max(worst, c.map.eval(d).average() / double(t.pdf(d)));
    }
    EXPECT_LE(worst, bound * 1.0001) << c.name;
  }
}

// The harness can fail: a density 10% off on alternate rows is rejected, while the map's own
// density, average(texel) / integral (no floor, no peak bound), passes.
TEST(MapTexels, TexelChiSquareRejectsAWrongDensity) {
  const EnvironmentMap map = random_map(32, 16, 21);
  const ImportanceTable t(map, map_options(2, 0, 0));
  struct Tilted {
    const ImportanceTable& t;
    const EnvironmentMap& map;
    DirectionSample sample(Point2 u) const { return t.sample(u); }
    float pdf(Vec3 d) const {
      const TexelCoord c = map.texel_coord(direction_to_latlong(map.to_map(d)));
      return t.pdf(d) * (c.y % 2 ? 1.1f : 0.9f);
    }
  };
  EXPECT_FALSE(texel_chi2(Tilted{t, map}, map, 1).passed);
  struct MapsOwn {
    const ImportanceTable& t;
    const EnvironmentMap& map;
    DirectionSample sample(Point2 u) const { return t.sample(u); }
    float pdf(Vec3 d) const { return map.eval(d).average() / float(t.integral()); }
  };
  EXPECT_TRUE(texel_chi2(MapsOwn{t, map}, map, 1).passed);
}

TEST(MapTexels, BlackMapIsEmpty) {
  const EnvironmentMap black = EnvironmentMap::from_pixels(8, 4, std::vector<float>(8 * 4 * 3, 0.0f));
  const ImportanceTable t(black, map_options(2));
  EXPECT_TRUE(t.empty());
  EXPECT_EQ(t.pdf({0, 0, 1}), 0.0f);
  EXPECT_EQ(t.sample({0.3f, 0.4f}).pdf, 0.0f);
}

}  // namespace
}  // namespace envpis
