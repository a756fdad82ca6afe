// SPDX-License-Identifier: Apache-2.0
// `envpis compare`, run as a command: clean one-line errors for bad options, and a small comparison
// whose metrics.json is checked against the images it wrote (relMSE and the tail recomputed from the EXR
// files with OpenImageIO, per image and per object), the reference cache, and the report files. Also its
// image metrics (apps/envpis/metrics.cpp) on a hand-built image.
#include <gtest/gtest.h>
#include "cli_util.h"
#include "metrics.h"
#include "test_util.h"
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kReportDir = std::string(ENVPIS_SOURCE_DIR) + "/report";

using envpis::test::CmdResult;

// `args` starts with "compare"; the report templates come from the source tree.
std::string with_report_dir(const std::string& args) {
  const std::string rest = args.size() > 7 ? args.substr(7) : std::string();
  return "compare --report-dir " + envpis::test::shell_quote(kReportDir) + rest;
}

std::vector<std::pair<std::string, std::string>> with_report_dir(std::vector<std::pair<std::string, std::string>> cases) {
  for (auto& c : cases) c.first = with_report_dir(c.first);
  return cases;
}

CmdResult run(const std::string& args) { return envpis::test::run_envpis(with_report_dir(args)); }

std::vector<float> read_rgb(const fs::path& path, int* w, int* h, int channels = 3) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) return {};
  *w = in->spec().width;
  *h = in->spec().height;
  std::vector<float> px(static_cast<std::size_t>(*w) * *h * channels);
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  return px;
}

// Five pixels with known errors against a grey reference of 1 (pixel 3: black): exact, 9x off, 11x off,
// 0.5 over black, and one channel 21x off. Only pixels 2 and 4 are more than 10x off (e > 100).
TEST(CompareMetrics, TailOfAHandBuiltImage) {
  using namespace envpis::app;
  const std::vector<float> ref{1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1};
  const std::vector<float> img{1, 1, 1, 10, 10, 10, 12, 12, 12, 0.5f, 0.5f, 0.5f, 1, 1, 22};
  const std::vector<float> var(5, 0.0f);
  const std::vector<int> ids{0, 0, 1, -1, 1};
  const ImageMetrics m = measure(NoisyImage{img, var}, NoisyImage{ref, var}, ids, {0, 1});
  const double e[5] = {0, 81 / 1.01, 121 / 1.01, 0.25 / 0.01, 441 / 1.01 / 3};
  auto near = [](double want) { return 1e-12 * want; };
  ASSERT_EQ(m.per_pixel.size(), 5u);
  for (int p = 0; p < 5; ++p) EXPECT_NEAR(m.per_pixel[p], e[p], 1e-6 * e[p]) << p;
  EXPECT_EQ(m.image.pixels, 5u);
  EXPECT_NEAR(m.image.relmse, (e[1] + e[2] + e[3] + e[4]) / 5, near(e[4]));
  EXPECT_NEAR(m.image.max_rel_sq_error, e[4], near(e[4]));
  EXPECT_EQ(m.image.pixels_over_10x, 2u);
  ASSERT_EQ(m.regions.size(), 2u);
  EXPECT_NEAR(m.regions[0].relmse, e[1] / 2, near(e[1]));
  EXPECT_NEAR(m.regions[0].max_rel_sq_error, e[1], near(e[1]));
  EXPECT_EQ(m.regions[0].pixels_over_10x, 0u) << "9x off is not more than 10x off";
  EXPECT_NEAR(m.regions[1].relmse, (e[2] + e[4]) / 2, near(e[4]));
  EXPECT_NEAR(m.regions[1].max_rel_sq_error, e[4], near(e[4]));
  EXPECT_EQ(m.regions[1].pixels_over_10x, 2u);
  // An object with no pixel: NaN metrics, no pixel over.
  const ImageMetrics none = measure(NoisyImage{img, var}, NoisyImage{ref, var}, ids, {7});
  EXPECT_TRUE(std::isnan(none.regions[0].relmse));
  EXPECT_TRUE(std::isnan(none.regions[0].max_rel_sq_error));
  EXPECT_EQ(none.regions[0].pixels_over_10x, 0u);
}

// The robust figures of the same image: without its worst ceil(0.1%) pixels (one here) and the median;
// one huge pixel moves the relMSE but neither of them.
TEST(CompareMetrics, TrimmedAndMedianIgnoreOneHugePixel) {
  using namespace envpis::app;
  const std::vector<float> ref{1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1};
  std::vector<float> img{1, 1, 1, 10, 10, 10, 12, 12, 12, 0.5f, 0.5f, 0.5f, 1, 1, 22};
  const std::vector<float> var(5, 0.0f);
  const std::vector<int> ids{0, 0, 1, -1, 1};
  const double e[5] = {0, 81 / 1.01, 121 / 1.01, 0.25 / 0.01, 441 / 1.01 / 3};
  const ImageMetrics m = measure(NoisyImage{img, var}, NoisyImage{ref, var}, ids, {0, 1});
  EXPECT_NEAR(m.image.relmse_trimmed, (e[1] + e[2] + e[3]) / 4, 1e-9);  // e[4], the worst, left out
  EXPECT_NEAR(m.image.median_rel_sq_error, e[1], 1e-9);
  EXPECT_NEAR(m.regions[0].relmse_trimmed, 0, 1e-12);  // two pixels: the worst of them left out
  EXPECT_NEAR(m.regions[1].median_rel_sq_error, (e[2] + e[4]) / 2, 1e-9);
  img[14] = 1e6f;  // a firefly in the worst pixel
  const ImageMetrics f = measure(NoisyImage{img, var}, NoisyImage{ref, var}, ids, {0, 1});
  EXPECT_GT(f.image.relmse, 1e10);
  EXPECT_DOUBLE_EQ(f.image.relmse_trimmed, m.image.relmse_trimmed);
  EXPECT_DOUBLE_EQ(f.image.median_rel_sq_error, m.image.median_rel_sq_error);
  EXPECT_TRUE(std::isnan(trimmed_mean({})));
  EXPECT_EQ(trimmed_mean({5}), 5);  // never all: one pixel stays
  std::vector<double> many(2500, 1.0);
  many[0] = many[1] = many[2] = 1e9;  // ceil(2.5) = 3 left out
  EXPECT_EQ(trimmed_mean(many), 1.0);
}

// The light samples' share of the variance, weighted as relMSE weighs each pixel: 1 / (R^2 + 0.01).
TEST(CompareMetrics, LightVarianceShare) {
  using namespace envpis::app;
  const std::vector<float> ref{1, 1, 1, 0, 0, 0};
  const std::vector<float> img{1, 1, 1, 0, 0, 0};
  const std::vector<float> var{2, 0.01f}, light{1, 0.01f}, ref_var(2, 0.0f);
  const std::vector<int> ids{0, 1};
  const ImageMetrics m = measure(NoisyImage{img, var, &light}, NoisyImage{ref, ref_var}, ids, {0, 1});
  EXPECT_NEAR(m.regions[0].light_variance_share, 0.5, 1e-6);
  EXPECT_NEAR(m.regions[1].light_variance_share, 1.0, 1e-6);
  // Whole image: (1 / 1.01 + 0.01 / 0.01) / (2 / 1.01 + 0.01 / 0.01)
  EXPECT_NEAR(m.image.light_variance_share, (1 / 1.01 + 1) / (2 / 1.01 + 1), 1e-6);
  const ImageMetrics unknown = measure(NoisyImage{img, var}, NoisyImage{ref, ref_var}, ids, {0});
  EXPECT_TRUE(std::isnan(unknown.image.light_variance_share));
}

TEST(CompareMetrics, Median) {
  using envpis::app::median;
  EXPECT_EQ(median({3, 1, 2}), 2);
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_EQ(median({5}), 5);
  EXPECT_TRUE(std::isnan(median({})));
}

// Each pixel's relative squared error, recomputed here from the written images (the command's own
// computation is in apps/envpis/metrics.cpp).
std::vector<double> rel_sq_errors(const std::vector<float>& img, const std::vector<float>& ref) {
  std::vector<double> e(ref.size() / 3, 0.0);
  for (std::size_t p = 0; p < e.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      const double I = img[p * 3 + c], R = ref[p * 3 + c];
      e[p] += (I - R) * (I - R) / (R * R + 0.01);
    }
    e[p] /= 3;
  }
  return e;
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

class CompareCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(envpis::test::envpis_binary()))
      GTEST_SKIP() << "the envpis command is not built (" << envpis::test::envpis_binary() << ")";
  }
};

TEST_F(CompareCommand, RejectsBadOptionsWithOneLineErrors) {
  const fs::path out = fs::temp_directory_path() / ("envpis-test-compare-bad-" + std::to_string(::getpid()));
  const std::string o = " --out '" + out.string() + "'";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"compare --spp 0" + o, "--spp"},
      {"compare --spp abc" + o, "--spp"},
      {"compare --ref-spp 4 --spp 8" + o, "--ref-spp"},
      {"compare --strategies mis,foo" + o, "unknown strategy 'foo'"},
      {"compare --strategies mis,mis" + o, "listed twice"},
      {"compare --strategies ," + o, "--strategies"},
      {"compare --equal-time -1" + o, "--equal-time"},
      {"compare --equal-time soon" + o, "--equal-time"},
      {"compare --integrator bidir" + o, "integrator"},
      {"compare --oracle-dirs 3" + o, "square"},
      {"compare --width -5" + o, "--width"},
      {"compare --seed 1 --ref-seed 1" + o, "--ref-seed"},
      {"compare --seeds 0" + o, "--seeds: must be in 1..64, got '0'"},
      {"compare --seeds abc" + o, "--seeds: expected an integer in 1..64, got 'abc'"},
      {"compare --seeds 65" + o, "--seeds: must be in 1..64, got '65'"},
      {"compare --seeds 2.5" + o, "--seeds: expected an integer in 1..64, got '2.5'"},
      {"compare --seed 2 --seeds 3 --ref-seed 4" + o, "--ref-seed 4 is one of the measured seeds 2..4 (--seed, --seeds)"},
      {"compare --env /nonexistent/map.exr" + o, "cannot load environment map '/nonexistent/map.exr': no such file"},
      {"compare --scene nosuchscene" + o, "unknown scene"},
      {"compare --env-orientation legacy" + o, "--env-orientation needs --env"},
      {"compare --env x.exr --env-filter cubic" + o, "--env-filter: unknown map filter 'cubic'"},
      {"compare --analysis-points 0" + o, "--analysis-points: must be in 1..10000, got '0'"},
      {"compare --analysis-points many" + o, "--analysis-points: expected an integer in 1..10000, got 'many'"},
      {"compare --analysis-points 10001" + o, "--analysis-points: must be in 1..10000, got '10001'"},
      {"compare --no-analysis --analysis-points 2" + o, "--analysis-points cannot be combined with --no-analysis"},
      {"compare --filter-glossy -1" + o, "--filter-glossy: must be >= 0 (0: off), got '-1'"},
      {"compare --clamp-direct nan" + o, "--clamp-direct: expected a finite number, got 'nan'"},
      {"compare --clamp-indirect inf" + o, "--clamp-indirect: expected a finite number, got 'inf'"},
      {"compare --caustics glossy" + o, "--caustics: unknown caustics 'glossy'"},
      {"compare --product-compensation sometimes" + o,
       "--product-compensation: unknown product compensation 'sometimes' (expected off, elsewhere, deeper, on, on-without-portals or auto)"},
      {"compare", "--out is required"},
      {"compare --out /proc/envpis-cannot-write", "--out"},
  };
  envpis::test::expect_one_line_errors(with_report_dir(cases));
  std::error_code ec;
  fs::remove_all(out, ec);
}

TEST_F(CompareCommand, SmallRunWritesConsistentMetricsImagesAndReport) {
  const std::string pid = std::to_string(::getpid());
  const fs::path out = fs::temp_directory_path() / ("envpis-test-compare-run-" + pid);
  const fs::path cache = fs::temp_directory_path() / ("envpis-test-compare-cache-" + pid);
  std::error_code ec;
  fs::remove_all(out, ec);
  fs::remove_all(cache, ec);
  const std::string args = "compare --scene fig1 --width 64 --height 12 --spp 4 --ref-spp 64 --strategies mis,product,oracle "
                           "--oracle-res 48 --oracle-dirs 1 --equal-time auto --repeats 1 --no-plots --no-analysis --quiet "
                           "--cache-dir '" + cache.string() + "' --out '" + out.string() + "'";
  const CmdResult r = run(args);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("report "), std::string::npos) << r.output;

  json m;
  std::ifstream(out / "metrics.json") >> m;
  EXPECT_EQ(m["width"], 64);
  EXPECT_EQ(m["height"], 12);
  EXPECT_EQ(m["reference"]["strategy"], "mis");
  EXPECT_EQ(m["closed_surfaces"], true);
  EXPECT_EQ(m["top_resolution"], 12);
  EXPECT_EQ(m["environment_lookup"]["orientation"], "panorama");
  EXPECT_EQ(m["environment_lookup"]["filter"], "bilinear");
  EXPECT_NE(m["reference"]["seed"], m["seed"]) << "the reference must use another seed";
  EXPECT_FALSE(m["reference"]["cached"].get<bool>());
  EXPECT_TRUE(m["plots"].is_null());
  EXPECT_TRUE(m["plots_unavailable"].is_string());
  EXPECT_TRUE(m["analysis"].is_null()) << "--no-analysis";
  EXPECT_FALSE(m.contains("analysis_unavailable"));
  ASSERT_TRUE(m["overhead"].is_object());
  EXPECT_EQ(m["regularized"], false);
  EXPECT_EQ(m["regularization"]["caustics"], "reflective,refractive");
  EXPECT_EQ(m["product_options"]["compensation"], "deeper") << "auto, direct light";
  EXPECT_EQ(m["product_options"]["proxy_lobe"], "half-vector") << "the command's default, not the library's";
  EXPECT_GT(m["overhead"]["ratio"].get<double>(), 0);
  ASSERT_EQ(m["regions"].size(), 8u) << "fig1: one region per sphere";
  EXPECT_EQ(m["regions"][0]["name"], "conductor-0.02");

  int W = 0, H = 0;
  const std::vector<float> ref = read_rgb(out / "images" / "reference.exr", &W, &H);
  ASSERT_EQ(W, 64);
  ASSERT_EQ(H, 12);
  int iw = 0, ih = 0;
  const std::vector<float> ids = read_rgb(out / "images" / "object-id.exr", &iw, &ih, 1);
  ASSERT_EQ(ids.size(), static_cast<std::size_t>(W) * H);

  for (const char* block : {"equal_spp", "equal_time"}) {
    ASSERT_TRUE(m[block].is_object()) << block;
    ASSERT_EQ(m[block]["strategies"].size(), 3u) << block;
    for (const auto& s : m[block]["strategies"]) {
      for (const char* k : {"spp", "seconds", "relmse", "efficiency", "mean", "nan_count", "regions", "max_rel_sq_error",
                            "pixels_over_10x"})
        EXPECT_TRUE(s.contains(k)) << block << " " << s["strategy"] << " lacks " << k;
      int w = 0, h = 0;
      const std::vector<float> img = read_rgb(out / s["images"]["exr"].get<std::string>(), &w, &h);
      ASSERT_EQ(img.size(), ref.size());
      double total = 0, max_e = 0;
      int over = 0;
      std::vector<double> region_sum(8, 0), region_n(8, 0), region_max(8, 0), region_over(8, 0);
      const std::vector<double> errors = rel_sq_errors(img, ref);
      for (std::size_t p = 0; p < ids.size(); ++p) {
        const double e = errors[p];
        total += e;
        max_e = std::max(max_e, e);
        over += e > 100;
        const int id = static_cast<int>(ids[p]);
        if (id >= 0 && id < 8) {
          region_sum[id] += e;
          region_n[id] += 1;
          region_max[id] = std::max(region_max[id], e);
          region_over[id] += e > 100;
        }
      }
      const double relmse = total / double(ids.size());
      EXPECT_NEAR(s["relmse"].get<double>(), relmse, 1e-6 * relmse + 1e-12) << block << " " << s["strategy"];
      EXPECT_NEAR(s["efficiency"].get<double>(), 1.0 / (relmse * s["seconds"].get<double>()),
                  1e-4 * s["efficiency"].get<double>());
      EXPECT_NEAR(s["max_rel_sq_error"].get<double>(), max_e, 1e-6 * max_e) << block << " " << s["strategy"];
      EXPECT_EQ(s["pixels_over_10x"].get<int>(), over) << block << " " << s["strategy"];
      for (const auto& reg : s["regions"]) {
        const int id = reg["id"];
        ASSERT_GT(region_n[id], 0);
        const double want = region_sum[id] / region_n[id];
        EXPECT_NEAR(reg["relmse"].get<double>(), want, 1e-6 * want + 1e-12) << s["strategy"] << " region " << id;
        EXPECT_NEAR(reg["max_rel_sq_error"].get<double>(), region_max[id], 1e-6 * region_max[id]) << s["strategy"] << " region " << id;
        EXPECT_EQ(reg["pixels_over_10x"].get<double>(), region_over[id]) << s["strategy"] << " region " << id;
        // The robust figures lie below the relMSE, which a few worst pixels can decide.
        EXPECT_LE(reg["relmse_trimmed"].get<double>(), reg["relmse"].get<double>() * (1 + 1e-9)) << s["strategy"];
        EXPECT_LE(reg["median_rel_sq_error"].get<double>(), reg["max_rel_sq_error"].get<double>()) << s["strategy"];
        EXPECT_TRUE(reg.contains("light_variance_share")) << s["strategy"];
      }
      for (const char* k : {"png", "error_png"}) EXPECT_TRUE(fs::exists(out / s["images"][k].get<std::string>()));
    }
  }
  // Convergence: 1, 2, 4 spp for each strategy, the last point equal to the equal-spp measurement.
  for (const char* s : {"mis", "product", "oracle"}) {
    const auto& series = m["convergence"][s];
    ASSERT_EQ(series.size(), 3u) << s;
    EXPECT_EQ(series[0]["spp"], 1);
    EXPECT_EQ(series[2]["spp"], 4);
  }
  EXPECT_TRUE(fs::exists(out / "index.html"));
  {
    std::ifstream in(out / "index.html");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string html = ss.str();
    EXPECT_EQ(html.find("{{"), std::string::npos) << "template placeholders left";
    EXPECT_EQ(html.find("http://"), std::string::npos);
    EXPECT_EQ(html.find("https://"), std::string::npos);
  }

  // Second run: the reference comes from the cache, bit-identical.
  const CmdResult r2 = run(args);
  ASSERT_EQ(r2.code, 0) << r2.output;
  json m2;
  std::ifstream(out / "metrics.json") >> m2;
  EXPECT_TRUE(m2["reference"]["cached"].get<bool>());
  int w2 = 0, h2 = 0;
  EXPECT_EQ(read_rgb(out / "images" / "reference.exr", &w2, &h2), ref);
  EXPECT_EQ(m2["equal_spp"]["strategies"][0]["relmse"], m["equal_spp"]["strategies"][0]["relmse"]);

  // The lat-long orientation and the filter are part of the reference's cache key.
  if (envpis::test::have_blender_maps()) {
    const std::string env = " --env '" + envpis::test::blender_map("sunset") + "'";
    for (const char* lookup : {"", " --env-orientation legacy", " --env-filter nearest"}) {
      const CmdResult r3 = run(args + env + lookup);
      ASSERT_EQ(r3.code, 0) << r3.output;
      json m3;
      std::ifstream(out / "metrics.json") >> m3;
      EXPECT_FALSE(m3["reference"]["cached"].get<bool>()) << lookup;
    }
  }
  fs::remove_all(out, ec);
  fs::remove_all(cache, ec);
}

// --product-compensation auto (the default) resolves by the integrator: the compensated product at
// every vertex along paths, the plain product at a camera ray's hit with direct light (docs/assets.md,
// "`auto`"); an explicit value is kept with either.
TEST_F(CompareCommand, ProductCompensationAutoFollowsTheIntegrator) {
  const std::string pid = std::to_string(::getpid());
  const fs::path out = fs::temp_directory_path() / ("envpis-test-compare-comp-" + pid);
  const fs::path cache = fs::temp_directory_path() / ("envpis-test-compare-comp-cache-" + pid);
  std::error_code ec;
  const std::string common = "compare --scene fig1 --width 16 --height 4 --spp 1 --ref-spp 4 --strategies product "
                             "--repeats 1 --no-convergence --no-plots --no-analysis --quiet --cache-dir '" +
                             cache.string() + "' --out '" + out.string() + "'";
  const std::vector<std::pair<std::string, std::string>> cases{{"--integrator path", "on-without-portals"},
                                                               {"--integrator direct", "deeper"},
                                                               {"--integrator path --product-compensation deeper", "deeper"}};
  for (const auto& [args, expected] : cases) {
    fs::remove_all(out, ec);
    const CmdResult r = run(common + " " + args);
    ASSERT_EQ(r.code, 0) << args << ": " << r.output;
    json m;
    std::ifstream(out / "metrics.json") >> m;
    EXPECT_EQ(m["product_options"]["compensation"], expected) << args;
  }
  fs::remove_all(out, ec);
  fs::remove_all(cache, ec);
}

// --seeds 3: three independent renders per strategy (seeds 2, 3, 4; the reference's seed 5 is next to
// them), each seed's relMSE and tail listed, the headline numbers their medians. Each seed's numbers
// are those of a one-seed run with that seed; the first seed's are those of the images written.
TEST_F(CompareCommand, SeedsReportMediansOverIndependentRenders) {
  const std::string pid = std::to_string(::getpid());
  const fs::path out = fs::temp_directory_path() / ("envpis-test-compare-seeds-" + pid);
  const fs::path out1 = fs::temp_directory_path() / ("envpis-test-compare-seed3-" + pid);
  const fs::path cache = fs::temp_directory_path() / ("envpis-test-compare-seeds-cache-" + pid);
  std::error_code ec;
  for (const fs::path& d : {out, out1, cache}) fs::remove_all(d, ec);
  // env at 2 spp: the sun's reflections give pixels more than 10x off.
  const std::string common = "compare --scene fig1 --width 64 --height 12 --spp 2 --ref-spp 64 --strategies env,mis "
                             "--ref-seed 5 --equal-time auto --repeats 1 --no-convergence --no-plots --no-analysis --quiet "
                             "--cache-dir '" + cache.string() + "'";
  const CmdResult r = run(common + " --seed 2 --seeds 3 --out '" + out.string() + "'");
  ASSERT_EQ(r.code, 0) << r.output;
  const CmdResult r1 = run(common + " --seed 3 --out '" + out1.string() + "'");
  ASSERT_EQ(r1.code, 0) << r1.output;
  json m, m1;
  std::ifstream(out / "metrics.json") >> m;
  std::ifstream(out1 / "metrics.json") >> m1;
  EXPECT_EQ(m["seed"], 2);
  EXPECT_EQ(m["seeds"], json({2, 3, 4}));
  EXPECT_EQ(m1["seeds"], json({3}));
  EXPECT_EQ(m["reference"]["seed"], 5);

  int W = 0, H = 0;
  const std::vector<float> ref = read_rgb(out / "images" / "reference.exr", &W, &H);
  ASSERT_EQ(ref.size(), 64u * 12u * 3u);
  double tail_pixels = 0;
  for (const char* block : {"equal_spp", "equal_time"}) {
    ASSERT_TRUE(m[block].is_object()) << block;
    for (std::size_t i = 0; i < m[block]["strategies"].size(); ++i) {
      const json& s = m[block]["strategies"][i];
      const std::string what = std::string(block) + " " + s["strategy"].get<std::string>();
      std::vector<json> sets{s};
      for (const json& reg : s["regions"]) sets.push_back(reg);
      for (const json& x : sets) {
        for (const char* k : {"relmse", "max_rel_sq_error", "pixels_over_10x"}) {
          const std::vector<double> v = x[std::string(k) + "_seeds"].get<std::vector<double>>();
          ASSERT_EQ(v.size(), 3u) << what << " " << k;
          EXPECT_EQ(x[k].get<double>(), median_of(v)) << what << " " << k;
          EXPECT_EQ(x[std::string(k) + (k == std::string("relmse") ? "_max" : "_worst")].get<double>(),
                    *std::max_element(v.begin(), v.end())) << what << " " << k;
        }
        const std::vector<double> rel = x["relmse_seeds"].get<std::vector<double>>();
        EXPECT_EQ(x["relmse_median"], x["relmse"]) << what;
        EXPECT_EQ(x["relmse_min"].get<double>(), *std::min_element(rel.begin(), rel.end())) << what;
        EXPECT_TRUE(rel[0] != rel[1] && rel[1] != rel[2] && rel[0] != rel[2]) << what << ": the seeds are not independent";
      }
      const double relmse = s["relmse"].get<double>();
      EXPECT_NEAR(s["efficiency"].get<double>(), 1.0 / (relmse * s["seconds"].get<double>()), 1e-9 * s["efficiency"].get<double>())
          << what << ": efficiency from the median relMSE";
      // The first seed's numbers are those of the images written.
      int w = 0, h = 0;
      const std::vector<double> e = rel_sq_errors(read_rgb(out / s["images"]["exr"].get<std::string>(), &w, &h), ref);
      double total = 0, max_e = 0, over = 0;
      for (double x : e) {
        total += x;
        max_e = std::max(max_e, x);
        over += x > 100;
      }
      EXPECT_NEAR(s["relmse_seeds"][0].get<double>(), total / double(e.size()), 1e-6 * total / double(e.size())) << what;
      EXPECT_NEAR(s["max_rel_sq_error_seeds"][0].get<double>(), max_e, 1e-6 * max_e) << what;
      EXPECT_EQ(s["pixels_over_10x_seeds"][0].get<double>(), over) << what;
      tail_pixels += s["pixels_over_10x_worst"].get<double>();
      // The second seed is seed 3: the same numbers as the one-seed run with --seed 3 (same spp, same reference).
      const json& s1 = m1[block]["strategies"][i];
      if (s1["spp"] == s["spp"]) {
        EXPECT_EQ(s["relmse_seeds"][1], s1["relmse"]) << what;
        EXPECT_EQ(s["max_rel_sq_error_seeds"][1], s1["max_rel_sq_error"]) << what;
        EXPECT_EQ(s["pixels_over_10x_seeds"][1], s1["pixels_over_10x"]) << what;
      }
    }
  }
  EXPECT_GT(tail_pixels, 0) << "env at 2 spp should have pixels more than 10x off: the test does not exercise the count";
  for (const fs::path& d : {out, out1, cache}) fs::remove_all(d, ec);
}

// The exact variance analysis (on by default): metrics.json's "analysis" has, per object of fig1, V of
// every compared strategy and of env (added for the decomposition), the limits and the decomposition,
// all finite, the ratios those of the pooled values, and the numbers are those of `envpis analyze` with
// the same options (the same tables, points and seed). index.html embeds them. A coarse light table and
// one point per object keep it to a few seconds.
TEST_F(CompareCommand, AnalysisInMetricsAndReport) {
  const std::string pid = std::to_string(::getpid());
  const fs::path out = fs::temp_directory_path() / ("envpis-test-compare-analysis-" + pid);
  const fs::path analyze_json = fs::temp_directory_path() / ("envpis-test-analyze-" + pid + ".json");
  std::error_code ec;
  fs::remove_all(out, ec);
  const std::string options = "--scene fig1 --fine 96 --subcells 2 --oracle-res 8 --seed 3";
  const std::vector<CmdResult> r = envpis::test::run_envpis_all(
      {with_report_dir("compare " + options + " --width 32 --height 6 --spp 2 --ref-spp 4 --strategies mis,product "
                       "--analysis-points 1 --repeats 1 --no-convergence --no-plots --no-cache --quiet --out '" +
                       out.string() + "'"),
       "analyze " + options + " --points 1 --strategies mis,product,env --json '" + analyze_json.string() + "'"},
      2);
  ASSERT_EQ(r[0].code, 0) << r[0].output;
  ASSERT_EQ(r[1].code, 0) << r[1].output;
  EXPECT_NE(r[0].output.find("analysis  exact V of one sample at 8 shading points (1 per object)"), std::string::npos)
      << r[0].output;
  json m, ref;
  std::ifstream(out / "metrics.json") >> m;
  std::ifstream(analyze_json) >> ref;
  ASSERT_TRUE(m["analysis"].is_object()) << m.dump().substr(0, 2000);
  const json& a = m["analysis"];
  EXPECT_EQ(a["strategies"], json({"mis", "product", "env"}));
  EXPECT_EQ(a["exact_levels"], json({12, 24, 48}));
  EXPECT_EQ(a["points_per_object"], 1);
  EXPECT_EQ(a["points_analyzed"], 8);
  EXPECT_EQ(a["grid_resolution"], 96);
  EXPECT_EQ(a["heuristic"], "power");
  EXPECT_GT(a["seconds"].get<double>(), 0);
  ASSERT_EQ(a["objects"].size(), 8u) << "fig1: eight spheres";
  ASSERT_EQ(ref["objects"].size(), 8u);
  auto finite_positive = [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()) && x.get<double>() > 0; };
  for (std::size_t i = 0; i < 8; ++i) {
    const json& o = a["objects"][i];
    const std::string name = o["name"];
    EXPECT_EQ(o["name"], m["regions"][i]["name"]) << "the analysis' objects are the report's regions";
    EXPECT_EQ(o["points"], 1) << name;
    ASSERT_EQ(o["per_point"].size(), 1u) << name;
    for (const char* s : {"mis", "product", "env"}) {
      EXPECT_TRUE(finite_positive(o["v"][s])) << name << " v " << s << ": " << o["v"][s];
      EXPECT_TRUE(finite_positive(o["v_light"][s])) << name << " v_light " << s << ": " << o["v_light"][s];
      const double v = o["per_point"][0]["v"][s].get<double>();
      EXPECT_NEAR(o["v"][s].get<double>(), v, 1e-12 * v) << name << ": one point, its V is the object's";
    }
    EXPECT_TRUE(o["v_product_limit"].is_number() && o["v_product_limit"].get<double>() >= 0) << name;
    for (const char* t : {"12", "24", "48"}) EXPECT_TRUE(finite_positive(o["v_exact"][t])) << name << " exact-" << t;
    const json& q = o["ratios"];
    auto d = [](const json& x) { return x.get<double>(); };
    const std::pair<const char*, double> ratios[] = {
        {"env_light/product_light", d(o["v_light"]["env"]) / d(o["v_light"]["product"])},
        {"product_light/exact-12", d(o["v_light"]["product"]) / d(o["v_exact"]["12"])},
        {"exact-12/exact-48", d(o["v_exact"]["12"]) / d(o["v_exact"]["48"])},
        {"mis/product", d(o["v"]["mis"]) / d(o["v"]["product"])}};
    for (const auto& [key, want] : ratios) {
      ASSERT_TRUE(finite_positive(q[key])) << name << " " << key << ": " << q[key];
      EXPECT_NEAR(d(q[key]), want, 1e-12 * want) << name << " " << key;
    }
    // envpis analyze on the same scene, map, options and seed: the same numbers.
    const json& e = ref["objects"][i];
    EXPECT_EQ(e["name"], o["name"]);
    for (const char* s : {"mis", "product", "env"}) {
      EXPECT_NEAR(d(o["v"][s]), d(e["v"][s]), 1e-9 * d(e["v"][s])) << name << " " << s;
      EXPECT_NEAR(d(o["v_light"][s]), d(e["v_light"][s]), 1e-9 * d(e["v_light"][s])) << name << " " << s;
    }
    EXPECT_NEAR(d(o["v_exact"]["12"]), d(e["v_exact"]["12"]), 1e-9 * d(e["v_exact"]["12"])) << name;
    EXPECT_EQ(o["per_point"][0]["pixel"], e["per_point"][0]["pixel"]) << name;
  }
  // The sharpest lobe gains most from the product over env sampling alone: env / product > 1 there.
  EXPECT_GT(a["objects"][0]["ratios"]["env_light/product_light"].get<double>(), 1);

  std::ifstream in(out / "index.html");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string html = ss.str();
  EXPECT_NE(html.find("\"analysis\":{"), std::string::npos) << "index.html does not embed the analysis";
  EXPECT_NE(html.find("function analysisSection"), std::string::npos) << "report.js without the analysis table";
  fs::remove_all(out, ec);
  fs::remove(analyze_json, ec);
}

}  // namespace
