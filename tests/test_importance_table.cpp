// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <tbb/parallel_for.h>

#include <random>

#include "chi2.h"
#include "stress_maps.h"
#include "test_util.h"

using namespace envpis;
using namespace envpis::test;

namespace {

Chi2Result env_chi2(const ImportanceTable& table, std::uint64_t seed, int tests = 1, std::size_t samples = 300000) {
  Chi2Options opt = table_aligned(table.fine_resolution());
  opt.samples = samples;
  opt.seed = seed;
  opt.test_count = tests;
  return sampler_chi2(table, opt);
}

/// Stratified Monte Carlo estimate of the integral of pdf over the sphere.
double integrate_pdf(const std::function<float(Vec3)>& pdf, int n = 1000, std::uint64_t seed = 5) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(0, 1);
  double acc = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) acc += pdf(equal_area_square_to_sphere({(i + U(rng)) / n, (j + U(rng)) / n}));
  return acc * 4 * M_PI / (double(n) * n);
}

/// Monte Carlo estimate of the integral of pdf over the sphere with importance sampling from an
/// independently built table (other top and fine resolutions) mixed half and half with uniform
/// directions: low variance even for maps with a small, very bright sun.
double integrate_pdf_is(const std::function<float(Vec3)>& pdf, const EnvironmentMap& map, int n = 400000,
                        std::uint64_t seed = 6) {
  ImportanceTableOptions o;
  o.top_resolution = 7;
  o.fine_resolution = 301;
  const ImportanceTable helper(map, o);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(0, 1);
  double acc = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 d = U(rng) < 0.5f ? helper.sample({U(rng), U(rng)}).direction : random_direction(rng);
    const double q = 0.5 * helper.pdf(d) + 0.5 / (4 * M_PI);
    acc += pdf(d) / q;
  }
  return acc / n;
}

}  // namespace

TEST(ImportanceTable, FineResolutionRule) {
  const auto map = synthetic_latlong(1024, 512, [](int, int) { return 1.0f; });
  const ImportanceTable t(map);
  EXPECT_EQ(t.top_resolution(), 12);
  EXPECT_EQ(t.fine_resolution(), 1452);  // smallest multiple of 12 with N >= 2 sqrt(1024 * 512)
  EXPECT_EQ(t.cell_resolution(), 121);
  ImportanceTableOptions o;
  o.top_resolution = 8;
  o.fine_resolution = 100;
  const ImportanceTable t2(map, o);
  EXPECT_EQ(t2.fine_resolution(), 104);
  const auto tiny = synthetic_latlong(1, 1, [](int, int) { return 2.0f; });
  const ImportanceTable t3(tiny);
  EXPECT_EQ(t3.fine_resolution(), 12);
  EXPECT_EQ(t3.cell_resolution(), 1);
}

TEST(ImportanceTable, InvalidOptionsThrow) {
  const auto map = synthetic_sky(64, 32);
  for (int top : {0, -1, 1000}) {
    ImportanceTableOptions o;
    o.top_resolution = top;
    EXPECT_THROW(ImportanceTable(map, o), Error) << top;
  }
  ImportanceTableOptions o;
  o.floor = std::nanf("");
  EXPECT_THROW(ImportanceTable(map, o), Error);
  for (const auto& [top, sub] : std::vector<std::pair<int, int>>{{12, 0}, {12, 9}, {200, 8}}) {
    ImportanceTableOptions s;
    s.top_resolution = top;
    s.subdivision = sub;
    EXPECT_THROW(ImportanceTable(map, s), Error) << top << " x " << sub;
  }
}

// Sub-cells change how a sample walks down the levels, not the environment's density: a table with
// S x S sub-cells has the density of the same table without them (same N), and samples it.
TEST(ImportanceTable, SubcellsKeepTheEnvironmentDensity) {
  const auto map = synthetic_sky(256, 128);
  ImportanceTableOptions o;
  o.fine_resolution = 480;
  const ImportanceTable flat(map, o);
  for (int S : {2, 4, 8}) {
    o.subdivision = S;
    const ImportanceTable t(map, o);
    ASSERT_EQ(t.fine_resolution(), 480);
    ASSERT_EQ(t.subdivision(), S);
    std::mt19937_64 rng(S);
    for (int i = 0; i < 20000; ++i) {
      const Vec3 d = random_direction(rng);
      ASSERT_NEAR(t.pdf(d), flat.pdf(d), 2e-5f * flat.pdf(d)) << S;
      const int c = t.cell_of_direction(d);
      const Point2 p = equal_area_sphere_to_square(d);
      ASSERT_NEAR(t.pdf_in_cell(c, p), flat.pdf_in_cell(c, p), 2e-5f * flat.pdf_in_cell(c, p)) << S;
    }
    for (int c = 0; c < t.cell_count(); ++c) {
      ASSERT_NEAR(t.cell_probability(c), flat.cell_probability(c), 1e-6f);
      ASSERT_TRUE(t.subcells(c).valid());
    }
    const auto r = env_chi2(t, 40 + S, 3);
    EXPECT_TRUE(r.passed) << "S = " << S << ": " << r.message;
  }
}

// Every direction of a sub-cell lies inside the sub-cell's bounding cone.
TEST(ImportanceTable, SubcellConesContainTheirSubcells) {
  ImportanceTableOptions o;
  o.subdivision = 4;
  const ImportanceTable t(synthetic_sky(64, 32), o);
  const int T = t.top_resolution(), S = 4;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> U(0, 1);
  for (int c = 0; c < t.cell_count(); ++c)
    for (int s = 0; s < S * S; ++s) {
      const Cone& cone = t.subcell_cone(c, s);
      for (int i = 0; i < 50; ++i) {
        const float x = ((c % T) * S + s % S + U(rng)) / float(T * S), y = ((c / T) * S + s / S + U(rng)) / float(T * S);
        ASSERT_GE(dot(equal_area_square_to_sphere({x, y}), cone.axis), cone.cos_half_angle - 1e-6f) << c << " " << s;
      }
    }
}

TEST(ImportanceTable, CellConesContainEveryDirectionOfTheirCell) {
  const auto map = synthetic_sky(64, 32);
  for (int T : {3, 5, 12, 16}) {
    ImportanceTableOptions o;
    o.top_resolution = T;
    const ImportanceTable t(map, o);
    float min_cos = 1, max_cos = -1;
    for (int c = 0; c < t.cell_count(); ++c) {
      const Cone& cone = t.cell_cone(c);
      min_cos = std::min(min_cos, cone.cos_half_angle);
      max_cos = std::max(max_cos, cone.cos_half_angle);
      EXPECT_NEAR(cone.cos_half_angle * cone.cos_half_angle + cone.sin_half_angle * cone.sin_half_angle, 1.0f, 1e-5f);
      const int cx = c % T, cy = c / T;
      const int k = 96;  // dense grid including the cell's edges and corners
      for (int j = 0; j <= k; ++j)
        for (int i = 0; i <= k; ++i) {
          const Vec3 d = equal_area_square_to_sphere({(cx + float(i) / k) / T, (cy + float(j) / k) / T});
          ASSERT_GE(dot(d, cone.axis), cone.cos_half_angle) << "T=" << T << " cell " << c;
        }
    }
    if (T == 12) {  // the paper's 0.944; ours is computed per cell and a little tighter in places
      EXPECT_GT(min_cos, 0.93f);
      EXPECT_LT(max_cos, 0.97f);
    }
  }
}

// A point sampled in top cell c stays in c, as a point and through square -> sphere -> square, even
// at the extreme offsets: rounding once put a sample with offset 1 - 2^-24 in the last texel exactly on
// the far edge, in the neighbouring cell; when that cell's product weight was 0 (wholly below an
// opaque proxy's horizon) the product sampler returned the sample with pdf 0 (about 1 in 2e7 samples).
TEST(ImportanceTable, SamplesInACellStayInItThroughTheRoundTrip) {
  const auto map = synthetic_sky(256, 128);
  const float one_minus = 0x1.fffffep-1f;
  const Point2 extremes[] = {{0, 0}, {one_minus, one_minus}, {0, one_minus}, {one_minus, 0}, {0.5f, 0.5f},
                             {1e-7f, 1 - 1e-7f}};
  for (int T : {5, 12, 16}) {
    ImportanceTableOptions o;
    o.top_resolution = T;
    const ImportanceTable t(map, o);
    for (int c = 0; c < t.cell_count(); ++c) {
      DiscreteDistribution2D only_c(T, T);  // a top level that always picks c: u reaches the fine level
      only_c.values()[c] = 1;
      only_c.update();
      for (const Point2& u : extremes) {
        const DirectionSample s = t.sample(only_c, u);
        ASSERT_EQ(s.cell, c);
        ASSERT_EQ(t.cell_of_direction(s.direction), c) << "T=" << T << " u=(" << u.x << "," << u.y << ")";
        ASSERT_GT(s.pdf, 0) << "T=" << T << " u=(" << u.x << "," << u.y << ")";
      }
    }
  }
}

TEST(ImportanceTable, EnvironmentSamplingChiSquare) {
  const int tests = 4;
  {
    const ImportanceTable t(synthetic_sky(256, 128));
    const auto r = env_chi2(t, 1, tests);
    EXPECT_TRUE(r.passed) << r.message;
  }
  {
    // equal-area source layout, rotated
    EnvironmentMapOptions o;
    o.rotation = Mat3::rotate_z(30);
    const auto m = synthetic_latlong(96, 96, [](int x, int y) { return 1.0f + float((x * 7 + y * 3) % 11); }, o);
    ASSERT_EQ(m.layout(), MapLayout::EqualArea);
    const ImportanceTable t(m);
    const auto r = env_chi2(t, 2, tests);
    EXPECT_TRUE(r.passed) << r.message;
  }
  if (have_blender_maps()) {
    for (const char* name : {"sunset", "studio"}) {
      const ImportanceTable t(EnvironmentMap::load(blender_map(name)));
      const auto r = env_chi2(t, 3, tests);
      EXPECT_TRUE(r.passed) << name << ": " << r.message;
    }
  }
}

TEST(ImportanceTable, PdfIntegratesToOneAndMatchesSample) {
  std::vector<EnvironmentMap> maps;
  maps.push_back(synthetic_sky());
  if (have_blender_maps()) maps.push_back(EnvironmentMap::load(blender_map("sunrise")));
  for (const auto& m : maps) {
    const ImportanceTable t(m);
    EXPECT_NEAR(integrate_pdf_is([&](Vec3 d) { return t.pdf(d); }, m), 1.0, 0.01);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<float> U(0, 1);
    for (int i = 0; i < 20000; ++i) {
      const DirectionSample s = t.sample({U(rng), U(rng)});
      ASSERT_GT(s.pdf, 0);
      ASSERT_NEAR(length(s.direction), 1.0f, 1e-5f);
      ASSERT_NEAR(s.pdf, t.pdf(s.direction), 1e-4f * s.pdf);
    }
  }
}

TEST(ImportanceTable, DensityPositiveWhereverRadianceIsPositive) {
  // Black lat-long maps with one bright texel: at the pole row (a texel far smaller than a table
  // texel), next to it, and at the equator. The bright texel must be importance sampled (its density
  // at least a good fraction of radiance / integral, not just the floor), and with the default floor
  // the density is positive in every direction, hence wherever the radiance is positive.
  for (int row : {0, 1, 64, 127}) {
    const int w = 512, h = 128, col = 77;
    const auto m = synthetic_latlong(w, h, [&](int x, int y) { return x == col && y == row ? 1000.0f : 0.0f; });
    for (float floor : {0.0f, 1e-4f}) {
      ImportanceTableOptions o;
      o.floor = floor;
      const ImportanceTable t(m, o);
      ASSERT_FALSE(t.empty());
      // Nearly all samples land within a few table texels of the bright texel.
      const Vec3 centre = m.to_world(latlong_to_direction({(col + 0.5f) / w, (row + 0.5f) / h}));
      // Within four map-resolution texel sides (the table is twice as fine as the map).
      const float cos_cap = std::cos(8.0f * std::sqrt(4 * kPi) / t.fine_resolution());
      int inside = 0;
      for (int i = 0; i < 4000; ++i)
        inside += dot(t.sample({(i + 0.5f) / 4000, std::fmod(i * 0.618034f, 1.0f)}).direction, centre) > cos_cap;
      EXPECT_GT(inside, 0.95 * 4000) << "row " << row << " floor " << floor;
      if (floor > 0) {
        const int n = 1200;
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const Vec3 d = equal_area_square_to_sphere({(i + 0.5f) / n, (j + 0.5f) / n});
            ASSERT_GT(t.pdf(d), 0.0f) << "row " << row;
          }
      }
    }
  }
}

// The table reads the map where eval does, under either lat-long orientation: its samples land on a
// single bright texel at the direction each convention gives it (written here without the library's
// formulas), and on a smooth map with no mirror symmetry its pdf is proportional to eval.
TEST(ImportanceTable, FollowsTheLatLongOrientation) {
  for (LatLongOrientation orientation : {LatLongOrientation::Panorama, LatLongOrientation::Legacy}) {
    EnvironmentMapOptions o;
    o.orientation = orientation;
    const bool pano = orientation == LatLongOrientation::Panorama;
    {
      const int w = 512, h = 256, col = 40, row = 100;
      const auto m = synthetic_latlong(w, h, [&](int x, int y) { return x == col && y == row ? 1000.0f : 0.0f; }, o);
      const ImportanceTable t(m);
      const double u = (col + 0.5) / w, theta = M_PI * (row + 0.5) / h;
      const double phi = pano ? 2 * M_PI * (0.5 - u) : 2 * M_PI * u;
      const Vec3 bright{float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                        float(std::cos(theta))};
      // Within four map-resolution texel sides (the table is twice as fine as the map).
      const float cos_cap = std::cos(8.0f * std::sqrt(4 * kPi) / t.fine_resolution());
      int inside = 0;
      for (int i = 0; i < 4000; ++i) {
        const DirectionSample s = t.sample({(i + 0.5f) / 4000, std::fmod(i * 0.618034f, 1.0f)});
        inside += dot(s.direction, bright) > cos_cap;
      }
      EXPECT_GT(inside, 0.95 * 4000) << to_string(orientation);
      EXPECT_GT(m.eval(bright).r, 100.0f) << to_string(orientation);
    }
    {
      const int w = 256, h = 128;
      const auto m = synthetic_latlong(w, h, [&](int x, int y) {
        return float(2.0 + 1.5 * std::cos(2 * M_PI * (x + 0.5) / w) * std::sin(M_PI * (y + 0.5) / h));
      }, o);
      const ImportanceTable t(m);
      // integral of eval over the sphere (the map is smooth: a uniform estimate is accurate enough)
      std::mt19937_64 rng(12);
      double integral = 0;
      const int n = 200000;
      for (int i = 0; i < n; ++i) integral += m.eval(random_direction(rng)).average();
      integral *= 4 * M_PI / n;
      double worst = 0;
      for (int i = 0; i < 5000; ++i) {
        const Vec3 d = random_direction(rng);
        worst = std::max(worst, std::abs(t.pdf(d) * integral / m.eval(d).average() - 1.0));
      }
      EXPECT_LT(worst, 0.1) << to_string(orientation);
    }
  }
}

TEST(ImportanceTable, SingleBrightPoleTexelIsSampledInProportionToItsEnergy) {
  // One texel on the top row of a 2048x64 map, next to a dim uniform background: its share of the
  // sampled directions must match its share of the energy.
  const int w = 2048, h = 64;
  const float bright = 2e6f;
  const auto m = synthetic_latlong(w, h, [&](int x, int y) { return x == 100 && y == 0 ? bright : 1.0f; });
  // With the peak bound (default) the texel, 1/25 of a table texel, lifts its neighbours to 1/K of its
  // radiance: it is then sampled more than its share, never less.
  const double texel_sr = 2 * M_PI / w * (1 - std::cos(M_PI / h));
  const double share = bright * texel_sr / (bright * texel_sr + 4 * M_PI);
  for (float peak_ratio : {0.0f, ImportanceTableOptions{}.peak_ratio}) {
    ImportanceTableOptions o;
    o.peak_ratio = peak_ratio;
    const ImportanceTable t(m, o);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<float> U(0, 1);
    const int n = 100000;
    int near_pole = 0;
    for (int i = 0; i < n; ++i)
      if (t.sample({U(rng), U(rng)}).direction.z > std::cos(1.5 * M_PI / h)) ++near_pole;
    if (peak_ratio == 0)
      EXPECT_NEAR(double(near_pole) / n, share, 0.03) << "share " << share;
    else
      EXPECT_GT(double(near_pole) / n, share - 0.03) << "share " << share;
  }
}

// The largest light-sample weight eval(d) / pdf(d), over the integral, at uniform directions and at
// directions crowded around each sun (where bilinear footprints and table texels disagree).
double worst_weight(const ImportanceTable& t, const EnvironmentMap& m, const std::vector<Sun>& suns) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> U(0, 1);
  double worst = 0;
  auto check = [&](Vec3 d) {
    const double p = t.pdf(d), L = m.eval(d).average();
    if (L > 0) worst = std::max(worst, p > 0 ? L / (p * t.integral()) : HUGE_VAL);
  };
  for (int i = 0; i < 200000; ++i) check(random_direction(rng));
  for (const Sun& s : suns) {
    const Vec3 n = s.direction;
    const Vec3 a = std::fabs(n.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 tx = normalize(cross(a, n)), ty = cross(n, tx);
    const float cap = std::cos(3 * (s.radius_degrees + 0.5f) * kPi / 180);
    for (int i = 0; i < 200000; ++i) {
      const float z = 1 - U(rng) * (1 - cap), r = std::sqrt(std::max(0.0f, 1 - z * z)), ph = 2 * kPi * U(rng);
      check(m.to_world(tx * (r * std::cos(ph)) + ty * (r * std::sin(ph)) + n * z));
    }
  }
  return worst;
}

TEST(ImportanceTable, PeakBoundCapsEveryLightSampleWeight) {
  // The documented guarantee: eval(d).average() / pdf(d) <= peak_ratio * integral for every d, on the
  // sun stress family and a single-texel spike. Without the bound (peak_ratio 0) the spike breaks it
  // by orders of magnitude, so this test can tell.
  std::vector<StressMap> maps = stress_family();
  maps.push_back({"spike", {}});
  for (const StressMap& sm : maps) {
    const EnvironmentMap m = sm.name == "spike"
                                 ? synthetic_latlong(1024, 512, [](int x, int y) { return x == 551 && y == 129 ? 1e5f : 1.0f; })
                                 : make_stress_map(sm);
    std::vector<Sun> suns = sm.suns;
    if (sm.name == "spike") suns.push_back({latlong_to_direction({551.5f / 1024, 129.5f / 512}), 0.2f, 1e5f});
    ImportanceTableOptions o;
    const ImportanceTable t(m, o);
    const double w = worst_weight(t, m, suns);
    EXPECT_LE(w, o.peak_ratio * 1.001) << sm.name;
    if (sm.name == "spike") {
      o.peak_ratio = 0;
      EXPECT_GT(worst_weight(ImportanceTable(m, o), m, suns), 10 * ImportanceTableOptions{}.peak_ratio);
    }
    if (sm.name == "cell-corner" || sm.name == "north-pole" || sm.name == "seam") {  // nearest look-ups too
      EnvironmentMapOptions mo;
      mo.filter = MapFilter::Nearest;
      const EnvironmentMap mn = make_stress_map(sm, 1024, 512, mo);
      EXPECT_LE(worst_weight(ImportanceTable(mn), mn, suns), ImportanceTableOptions{}.peak_ratio * 1.001) << sm.name;
    }
  }
}

TEST(ImportanceTable, MemoryWithinSingleLevelPlusOfT2) {
  const ImportanceTable t(synthetic_latlong(1024, 512, [](int x, int) { return 1.0f + x; }));
  const std::size_t T2 = std::size_t(t.cell_count());
  EXPECT_LE(t.bytes_used(), t.single_level_bytes() + 64 * T2 + 4096);
  EXPECT_GT(t.bytes_used(), 2 * sizeof(float) * 1452 * 1452);
}

TEST(ImportanceTable, AllBlackMapIsEmpty) {
  const ImportanceTable t(synthetic_latlong(64, 32, [](int, int) { return 0.0f; }));
  EXPECT_TRUE(t.empty());
  EXPECT_EQ(t.sample({0.3f, 0.7f}).pdf, 0.0f);
  EXPECT_EQ(t.pdf({0, 0, 1}), 0.0f);
}

TEST(ImportanceTable, ExtremeAndDegenerateMaps) {
  // 1e30 texels: no overflow in the sums and CDFs.
  {
    const auto m = synthetic_latlong(64, 32, [](int x, int y) { return (x + y) % 2 ? 1e30f : 1.0f; });
    const ImportanceTable t(m);
    EXPECT_FALSE(t.empty());
    EXPECT_NEAR(integrate_pdf([&](Vec3 d) { return t.pdf(d); }, 300), 1.0, 0.01);
    const auto r = env_chi2(t, 8, 10, 100000);
    EXPECT_TRUE(r.passed) << r.message;
  }
  // 1x1, 3x1, 1x1000 maps and top sizes 1 and 2.
  for (auto [w, h] : {std::pair{1, 1}, std::pair{3, 1}, std::pair{1, 1000}}) {
    const auto m = synthetic_latlong(w, h, [](int x, int y) { return 1.0f + x + 0.01f * y; });
    for (int top : {1, 2, 12}) {
      ImportanceTableOptions o;
      o.top_resolution = top;
      const ImportanceTable t(m, o);
      EXPECT_NEAR(integrate_pdf([&](Vec3 d) { return t.pdf(d); }, 200), 1.0, 0.01) << w << "x" << h << " T=" << top;
      const auto r = env_chi2(t, 10 + top, 10, 50000);
      EXPECT_TRUE(r.passed) << w << "x" << h << " T=" << top << ": " << r.message;
    }
  }
}

TEST(ImportanceTable, CompensatedIsZeroBelowTheMean) {
  const auto m = synthetic_sky(128, 64);
  ImportanceTableOptions o;
  o.compensated = true;
  const ImportanceTable t(m, o);
  const ImportanceTable plain(m);
  int zero = 0;
  std::mt19937_64 rng(2);
  for (int i = 0; i < 10000; ++i) zero += t.pdf(random_direction(rng)) == 0.0f;
  EXPECT_GT(zero, 1000);  // most of the dim sky is below the mean
  EXPECT_NEAR(integrate_pdf_is([&](Vec3 d) { return t.pdf(d); }, m), 1.0, 0.01);
  // A constant map falls back to the plain table.
  const ImportanceTable c(synthetic_latlong(32, 16, [](int, int) { return 3.0f; }), o);
  EXPECT_FALSE(c.empty());
  EXPECT_NEAR(c.pdf({0, 0, 1}), 1.0f / (4 * kPi), 0.03f / (4 * kPi));  // the table of a coarse 32x16 map
}

TEST(ImportanceTable, ThreadSafeConcurrentSampling) {
  const ImportanceTable t(synthetic_sky());
  const int n = 20000;
  std::vector<DirectionSample> serial(n), parallel(n);
  auto u = [](int i) { return Point2{float((i * 7919) % n) / n, float((i * 104729) % n) / n}; };
  for (int i = 0; i < n; ++i) serial[i] = t.sample(u(i));
  tbb::parallel_for(0, n, [&](int i) { parallel[i] = t.sample(u(i)); });
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(serial[i].pdf, parallel[i].pdf);
    ASSERT_EQ(serial[i].direction.x, parallel[i].direction.x);
  }
}

// Tables built together share the map's gather where their grid and peak ratio agree; each must be
// bit for bit the table its options build alone: plain, compensated, another floor, the oracle's
// shape (T 48, no sub-cells: the same grid as T 12 x S 4), another peak ratio, another grid and the
// map's own texels, on a map with a sun and on an all-black one.
TEST(ImportanceTable, BuiltTogetherEqualsBuiltAlone) {
  std::vector<ImportanceTableOptions> options(8);
  options[0].subdivision = 4;
  options[1] = options[0];
  options[1].compensated = true;
  options[2] = options[0];
  options[2].floor = 0.2f;
  options[3].top_resolution = 48;  // the oracle's: the same fine grid as options[0]
  options[4] = options[0];
  options[4].peak_ratio = 2.0f;
  options[5] = options[4];
  options[5].compensated = true;
  options[6].fine_resolution = 200;
  options[7].fine_texels = FineTexels::Map;
  const StressMap sun = stress_family().front();
  for (const EnvironmentMap& m : {make_stress_map(sun, 128, 64), synthetic_latlong(64, 32, [](int, int) { return 0.0f; })}) {
    const auto together = ImportanceTable::build_together(m, options);
    ASSERT_EQ(together.size(), options.size());
    std::mt19937_64 rng(9);
    for (std::size_t i = 0; i < options.size(); ++i) {
      SCOPED_TRACE("options " + std::to_string(i));
      const ImportanceTable alone(m, options[i]);
      const ImportanceTable& t = *together[i];
      ASSERT_EQ(t.empty(), alone.empty());
      ASSERT_EQ(t.fine_resolution(), alone.fine_resolution());
      EXPECT_EQ(t.integral(), alone.integral());
      for (int y = 0; y < t.importance_height(); ++y)
        for (int x = 0; x < t.importance_width(); ++x) ASSERT_EQ(t.importance(x, y), alone.importance(x, y));
      for (int k = 0; k < 2000; ++k) {
        const Vec3 d = random_direction(rng);
        ASSERT_EQ(t.pdf(d), alone.pdf(d));
      }
    }
  }
  options[0].top_resolution = 0;
  EXPECT_THROW(ImportanceTable::build_together(synthetic_sky(), options), Error);
}

// The cells' cones depend on the grid alone: tables on one grid (whatever their map) share one set, a
// table on another grid has its own, and a set computed again after every holder let go has the same
// values.
TEST(ImportanceTable, TablesOnOneGridShareTheirCones) {
  ImportanceTableOptions o;
  o.subdivision = 4;
  std::vector<Cone> before;
  {
    const ImportanceTable a(synthetic_sky(64, 32), o);
    const ImportanceTable b(make_stress_map(stress_family().front(), 128, 64), o);
    EXPECT_EQ(&a.cell_cone(7), &b.cell_cone(7));
    EXPECT_EQ(&a.subcell_cone(7, 3), &b.subcell_cone(7, 3));
    ImportanceTableOptions other = o;
    other.subdivision = 2;
    const ImportanceTable c(synthetic_sky(64, 32), other);
    EXPECT_NE(&a.subcell_cone(7, 3), &c.subcell_cone(7, 3));
    for (int k = 0; k < a.cell_count(); ++k)
      for (int s = 0; s < 16; ++s) before.push_back(a.subcell_cone(k, s));
  }
  const ImportanceTable again(synthetic_sky(32, 16), o);
  std::size_t i = 0;
  for (int k = 0; k < again.cell_count(); ++k)
    for (int s = 0; s < 16; ++s, ++i) {
      const Cone& c = again.subcell_cone(k, s);
      ASSERT_EQ(c.axis.x, before[i].axis.x);
      ASSERT_EQ(c.axis.y, before[i].axis.y);
      ASSERT_EQ(c.axis.z, before[i].axis.z);
      ASSERT_EQ(c.cos_half_angle, before[i].cos_half_angle);
      ASSERT_EQ(c.sin_half_angle, before[i].sin_half_angle);
    }
}
