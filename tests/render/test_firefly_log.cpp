// SPDX-License-Identifier: Apache-2.0
// The firefly log (render/firefly_log.h) on a map made to produce fireflies: a tiny, very bright sun
// (many of them: the stress family's sky with 48 suns of 0.4 degrees at 2e4, tests/stress_maps.h) under
// the old table (peak bound off, RenderOptions::light_table.peak_ratio = 0):
//   - it catches light samples, and each record's fields agree with each other and with the library
//     (contribution = beta * radiance * f|cos| * w / pdf, the MIS weight from the two pdfs, the light
//     pdf = LightSampler::pdf, the texel and cell of the direction, the texel's importance), and the
//     worst of them land in texels whose importance is far below the radiance eval returns there;
//   - the image is bit-identical with the log on and off, and the records do not depend on threading;
//   - a huge threshold logs nothing; max_records bounds what is kept;
//   - `envpis render --firefly-log` and `envpis compare --firefly-log` write CSV, and reject bad values
//     with one-line errors.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "test_util.h"
#include "render/render.h"
#include "render/scenes.h"
#include "stress_maps.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;

/// The stress family's sky with 48 small suns (0.4 degrees, 2e4) spread over the upper hemisphere: the
/// texels on their rims that the old table rates at sky level are hit often enough for a small test.
std::shared_ptr<const EnvironmentMap> sun_map() {
  static const auto env = [] {
    test::StressMap m{"many-suns", {}};
    for (int i = 0; i < 48; ++i)
      m.suns.push_back({test::polar(15.0f + 70.0f * float(i % 6) / 5.0f, 7.5f * float(i)), 0.4f, 2e4f});
    return std::make_shared<const EnvironmentMap>(test::make_stress_map(m));
  }();
  return env;
}

const Scene& sun_scene() {
  static const Scene scene = make_builtin_scene("fig1", sun_map());
  return scene;
}

RenderOptions options(Strategy s, int threads = 0) {
  RenderOptions o;
  o.strategy = s;
  o.integrator = IntegratorKind::Direct;
  o.width = 64;
  o.height = 16;
  o.spp = 256;
  // The old table (its resolution and no peak bound): texels next to the sun get sky-level importance.
  o.light_table.fine_resolution = 732;
  o.light_table.peak_ratio = 0;
  o.threads = threads;
  return o;
}

// Well above this image's average pixel (about 4): mostly the suns' light samples are logged.
constexpr float kThreshold = 50;

bool near(float a, float b, float rel) { return std::fabs(a - b) <= rel * std::max(std::fabs(a), std::fabs(b)) + 1e-30f; }

void expect_consistent(const FireflyRecord& r, const StrategyTables& tables, const FireflyLogOptions& log) {
  SCOPED_TRACE("pixel " + std::to_string(r.x) + "," + std::to_string(r.y) + " sample " + std::to_string(r.sample) +
               " " + to_string(r.technique));
  const bool light = r.technique == SampleTechnique::Light;
  const float pdf = light ? r.light_pdf : r.bsdf_pdf, other = light ? r.bsdf_pdf : r.light_pdf;
  const float threshold = log.pixel_threshold.empty() ? log.threshold : log.pixel_threshold[r.y * 64 + r.x];
  EXPECT_GT(r.contribution.average(), threshold);
  EXPECT_EQ(r.threshold, threshold);
  EXPECT_EQ(r.depth, 0);  // direct
  EXPECT_TRUE(r.object >= 0 && r.object < 8) << r.object;  // fig1's spheres
  const Rgb expect = r.beta * r.radiance * r.f_cos * (r.mis_weight / pdf);
  EXPECT_TRUE(near(r.contribution.r, expect.r, 1e-5f)) << r.contribution.r << " vs " << expect.r;
  EXPECT_TRUE(near(r.contribution.b, expect.b, 1e-5f)) << r.contribution.b << " vs " << expect.b;
  EXPECT_TRUE(near(r.mis_weight, power_heuristic(1, pdf, 1, other), 1e-5f));
  const Rgb L = sun_scene().environment().eval(r.direction);
  EXPECT_EQ(r.radiance.r, L.r);
  EXPECT_EQ(r.radiance.g, L.g);

  const ImportanceTable& table = *tables.table;
  const int T = table.top_resolution(), F = table.cell_resolution();
  EXPECT_EQ(r.cell, table.cell_of_direction(r.direction));
  EXPECT_EQ(r.texel_x / F + (r.texel_y / F) * T, r.cell);
  const Point2 p = equal_area_sphere_to_square(r.direction);
  EXPECT_LE(std::abs(r.texel_x - int(p.x * float(table.fine_resolution()))), 1);
  EXPECT_LE(std::abs(r.texel_y - int(p.y * float(table.fine_resolution()))), 1);
  EXPECT_EQ(r.texel_importance, table.importance(r.texel_x, r.texel_y));
  EXPECT_EQ(r.table_pdf, table.pdf(r.direction));
  EXPECT_EQ(r.cell_env_probability, table.cell_probability(r.cell));
  EXPECT_TRUE(near(table.solid_angle_pdf(r.cell_probability, r.pdf_in_cell), r.light_pdf, 1e-5f));
}

// With the old table some light samples land where eval returns far more than the texel's importance:
// the fireflies. With the peak bound (K = 8) none can (ImportanceTableOptions::peak_ratio).
TEST(FireflyLog, CatchesLightSamplesWithConsistentFieldsAndTheOldTablesFireflies) {
  for (const float K : {0.0f, 8.0f}) {
    SCOPED_TRACE("peak ratio " + std::to_string(K));
    RenderOptions o = options(Strategy::Mis);
    o.light_table.peak_ratio = K;
    o.spp = 1024;
    const StrategyTables tables = StrategyTables::build(sun_scene().environment(), Strategy::Mis, {}, {},
                                                        o.light_table);
    FireflyLogOptions log;
    log.threshold = kThreshold;
    o.firefly_log = &log;
    o.tables = &tables;
    const RenderResult r = render(sun_scene(), o);
    int light = 0, over_bound = 0, same_object = 0;
    float worst = 0;  // largest radiance / texel importance of a light sample
    const LightSampler sampler(tables);  // mis: the density does not depend on the shading point
    for (const FireflyRecord& f : r.fireflies) {
      expect_consistent(f, tables, log);
      same_object += f.object == r.object_id[static_cast<std::size_t>(f.y) * 64 + f.x];
      EXPECT_TRUE(near(f.light_pdf, sampler.pdf(f.direction), 1e-4f)) << f.light_pdf << " vs " << sampler.pdf(f.direction);
      EXPECT_TRUE(near(f.light_pdf, f.table_pdf, 1e-4f));
      if (f.technique != SampleTechnique::Light) continue;
      ++light;
      worst = std::max(worst, f.radiance.average() / f.texel_importance);
      if (f.radiance.average() > 1.001f * 8 * f.texel_importance) ++over_bound;
    }
    EXPECT_GE(light, 100) << r.fireflies.size() << " records";
    EXPECT_GT(same_object, 0.9 * double(r.fireflies.size()));  // but samples near a silhouette
    if (K == 0) {
      EXPECT_GE(over_bound, 10);
      EXPECT_GT(worst, 1000);
    } else {
      EXPECT_EQ(over_bound, 0) << "worst " << worst;
    }
    EXPECT_EQ(r.fireflies_dropped, 0u);
    EXPECT_TRUE(std::is_sorted(r.fireflies.begin(), r.fireflies.end(), [](const FireflyRecord& a, const FireflyRecord& b) {
      return std::make_tuple(a.y, a.x, a.sample) < std::make_tuple(b.y, b.x, b.sample);
    }));
  }
}

TEST(FireflyLog, ProductRecordsAreConsistentAndCarryTheProxy) {
  const RenderOptions o = options(Strategy::Product);
  const StrategyTables tables = StrategyTables::build(sun_scene().environment(), Strategy::Product, {}, {},
                                                      o.light_table);
  FireflyLogOptions log;
  log.threshold = 20;  // the sun's ordinary samples too: many records
  RenderOptions with = o;
  with.firefly_log = &log;
  with.tables = &tables;
  const RenderResult r = render(sun_scene(), with);
  ASSERT_FALSE(r.fireflies.empty());
  bool proxy = false;
  for (const FireflyRecord& f : r.fireflies) {
    expect_consistent(f, tables, log);
    EXPECT_GE(f.proxy_cell, 0.0f);
    EXPECT_GE(f.proxy_direction, 0.0f);
    proxy = proxy || f.proxy_cell > 0;
  }
  EXPECT_TRUE(proxy);
}

// Not named for scripts/sanitize.sh's tsan step ("Thread"/"Determinism"): with Debian's uninstrumented
// libtbb every TBB worker access is a (suppressed) report there, and this test's 1024x512 tables
// make thousands of them, each symbolized: minutes of CI for races TSan cannot judge (tsan.supp).
TEST(FireflyLog, ChangesNothingAndIsTheSameOnOneOrTwoWorkers) {
  for (Strategy s : {Strategy::Mis, Strategy::Product}) {
    SCOPED_TRACE(to_string(s));
    RenderOptions base = options(s);
    base.spp = 32;  // enough for many records; this test also runs under ThreadSanitizer
    const RenderResult off = render(sun_scene(), base);
    FireflyLogOptions log;
    log.threshold = 20;
    RenderOptions on = base;
    on.threads = 1;
    on.firefly_log = &log;
    const RenderResult one = render(sun_scene(), on);
    on.threads = 2;
    const RenderResult two = render(sun_scene(), on);
    EXPECT_EQ(off.rgb, one.rgb);
    EXPECT_EQ(off.variance, one.variance);
    ASSERT_FALSE(one.fireflies.empty());
    ASSERT_EQ(one.fireflies.size(), two.fireflies.size());
    for (std::size_t i = 0; i < one.fireflies.size(); ++i) {
      const FireflyRecord &a = one.fireflies[i], &b = two.fireflies[i];
      EXPECT_EQ(std::make_tuple(a.x, a.y, a.sample, a.depth, a.technique, a.contribution.r, a.light_pdf),
                std::make_tuple(b.x, b.y, b.sample, b.depth, b.technique, b.contribution.r, b.light_pdf));
    }
  }
}

TEST(FireflyLog, HugeThresholdLogsNothingAndMaxRecordsBoundsTheLog) {
  FireflyLogOptions log;
  log.threshold = 1e30f;
  RenderOptions o = options(Strategy::Mis);
  o.firefly_log = &log;
  EXPECT_TRUE(render(sun_scene(), o).fireflies.empty());

  log.threshold = 1e-3f;  // nearly every contribution
  log.max_records = 10;
  const RenderResult r = render(sun_scene(), o);
  EXPECT_EQ(r.fireflies.size(), 10u);
  EXPECT_GT(r.fireflies_dropped, 1000u);
}

TEST(FireflyLog, PerPixelThresholdsAndValidation) {
  RenderOptions o = options(Strategy::Mis);
  FireflyLogOptions log;
  o.firefly_log = &log;
  EXPECT_THROW(render(sun_scene(), o), Error);  // threshold 0
  log.threshold = std::nanf("");
  EXPECT_THROW(render(sun_scene(), o), Error);
  log.pixel_threshold.assign(5, 1.0f);  // wrong size
  EXPECT_THROW(render(sun_scene(), o), Error);
  // Only the left half of the image is logged.
  log.pixel_threshold.assign(64 * 16, 1e30f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) log.pixel_threshold[y * 64 + x] = 20;
  const RenderResult r = render(sun_scene(), o);
  ASSERT_FALSE(r.fireflies.empty());
  for (const FireflyRecord& f : r.fireflies) {
    EXPECT_LT(f.x, 32);
    EXPECT_EQ(f.threshold, 20.0f);
  }
}

// ------------------------------------------------------------------------------------------ command

using test::TempDir;

std::string first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::size_t line_count(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

TEST(FireflyLogCommand, RenderAndCompareWriteCsvAndRejectBadValues) {
  if (!fs::exists(test::envpis_binary())) GTEST_SKIP() << "envpis not built";
  TempDir dir;
  const std::string out = (dir.path / "o.exr").string(), csv = (dir.path / "f.csv").string();
  const std::string small = "--scene fig1 --width 32 --height 8 --spp 4 --integrator direct ";
  const std::string compare = small + "--ref-spp 8 --repeats 1 --no-cache --no-plots --no-convergence --no-analysis --quiet "
                                      "--strategies mis --out " + (dir.path / "cmp").string() + " ";
  const std::vector<std::pair<std::string, std::string>> bad{
      {"render " + small + "--out " + out + " --firefly-log " + csv, "--firefly-log needs --firefly-threshold"},
      {"render " + small + "--out " + out + " --firefly-threshold 5", "--firefly-threshold needs --firefly-log"},
      {"render " + small + "--out " + out + " --firefly-log " + csv + " --firefly-threshold 0", "--firefly-threshold: must be > 0"},
      {"render " + small + "--out " + out + " --firefly-log " + csv + " --firefly-threshold -1", "--firefly-threshold: must be > 0"},
      {"render " + small + "--out " + out + " --firefly-log " + csv + " --firefly-threshold abc", "--firefly-threshold: expected a finite number"},
      {"render " + small + "--out " + out + " --firefly-log " + csv + " --firefly-threshold nan", "--firefly-threshold: expected a finite number"},
      {"render " + small + "--out " + out + " --firefly-log /nonexistent-dir/f.csv --firefly-threshold 1", "cannot write --firefly-log"},
      {"compare " + compare + "--firefly-factor 3", "--firefly-factor needs --firefly-log"},
      {"compare " + compare + "--firefly-log " + (dir.path / "ff").string() + " --firefly-factor 0", "--firefly-factor: must be > 0"},
      {"compare " + compare + "--firefly-log " + (dir.path / "ff").string() + " --firefly-factor x", "--firefly-factor: expected a finite number"},
      {"compare " + compare + "--firefly-log " + out, "is not a directory"},
  };
  std::ofstream(out) << "x";  // an existing file, for compare's "not a directory"
  test::expect_one_line_errors(bad, 2);

  const std::string header = "x,y,sample,depth,object,technique,contribution,threshold,light_pdf,bsdf_pdf,mis_weight";
  const auto ok = test::run_envpis_all(
      {"render " + small + "--strategy mis --out " + out + " --firefly-log " + csv + " --firefly-threshold 0.5",
       "compare " + compare + "--firefly-log " + (dir.path / "ff").string() + " --firefly-factor 0.5"},
      2);
  ASSERT_EQ(ok[0].code, 0) << ok[0].output;
  EXPECT_NE(ok[0].output.find("fireflies"), std::string::npos) << ok[0].output;
  EXPECT_EQ(first_line(csv).rfind(header, 0), 0u) << first_line(csv);
  EXPECT_GT(line_count(csv), 1u);
  ASSERT_EQ(ok[1].code, 0) << ok[1].output;
  const std::string mis_csv = (dir.path / "ff" / "fireflies-mis.csv").string();
  EXPECT_EQ(first_line(mis_csv).rfind(header, 0), 0u) << first_line(mis_csv);
  EXPECT_GT(line_count(mis_csv), 1u);
}

}  // namespace
}  // namespace envpis::render
