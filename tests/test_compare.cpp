// `envpis compare`, run as a command: clean one-line errors for bad options, and a small comparison
// whose metrics.json is checked against the images it wrote (relMSE recomputed from the EXR files with
// OpenImageIO, per image and per object), the reference cache, and the report files.
#include <gtest/gtest.h>
#include "cli_util.h"
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

const std::string kEnvpis = std::string(ENVPIS_BINARY_DIR) + "/apps/envpis/envpis";
const std::string kReportDir = fs::path(ENVPIS_TEST_DATA).parent_path().parent_path().string() + "/report";

using envpis::test::CmdResult;

// `args` starts with "compare"; the report templates come from the source tree.
CmdResult run(const std::string& args) {
  const std::string rest = args.size() > 7 ? args.substr(7) : std::string();
  return envpis::test::run_envpis("compare --report-dir " + envpis::test::shell_quote(kReportDir) + rest);
}

std::vector<float> read_rgb(const fs::path& path, int* w, int* h, int channels = 3) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) return {};
  *w = in->spec().width;
  *h = in->spec().height;
  std::vector<float> px(static_cast<std::size_t>(*w) * *h * channels);
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  return px;
}

class CompareCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kEnvpis)) GTEST_SKIP() << "the envpis command is not built (" << kEnvpis << ")";
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
      {"compare --env /nonexistent/map.exr" + o, "cannot load environment map '/nonexistent/map.exr': no such file"},
      {"compare --scene nosuchscene" + o, "unknown scene"},
      {"compare --env-orientation legacy" + o, "--env-orientation needs --env"},
      {"compare --env x.exr --env-filter cubic" + o, "--env-filter: unknown map filter 'cubic'"},
      {"compare", "--out is required"},
      {"compare --out /proc/envpis-cannot-write", "--out"},
  };
  for (const auto& [args, needle] : cases) {
    const CmdResult r = run(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("envpis compare: error: "), std::string::npos) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << args << "\n" << r.output;
    // One line: the message and its newline, nothing else.
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << "\n" << r.output;
  }
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
                           "--oracle-res 8 --oracle-dirs 1 --equal-time auto --repeats 1 --no-plots --quiet "
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
  ASSERT_TRUE(m["overhead"].is_object());
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
      for (const char* k : {"spp", "seconds", "relmse", "efficiency", "mean", "nan_count", "regions"})
        EXPECT_TRUE(s.contains(k)) << block << " " << s["strategy"] << " lacks " << k;
      int w = 0, h = 0;
      const std::vector<float> img = read_rgb(out / s["images"]["exr"].get<std::string>(), &w, &h);
      ASSERT_EQ(img.size(), ref.size());
      double total = 0;
      std::vector<double> region_sum(8, 0), region_n(8, 0);
      for (std::size_t p = 0; p < ids.size(); ++p) {
        double e = 0;
        for (int c = 0; c < 3; ++c) {
          const double I = img[p * 3 + c], R = ref[p * 3 + c];
          e += (I - R) * (I - R) / (R * R + 0.01);
        }
        total += e / 3;
        const int id = static_cast<int>(ids[p]);
        if (id >= 0 && id < 8) {
          region_sum[id] += e / 3;
          region_n[id] += 1;
        }
      }
      const double relmse = total / double(ids.size());
      EXPECT_NEAR(s["relmse"].get<double>(), relmse, 1e-6 * relmse + 1e-12) << block << " " << s["strategy"];
      EXPECT_NEAR(s["efficiency"].get<double>(), 1.0 / (relmse * s["seconds"].get<double>()),
                  1e-4 * s["efficiency"].get<double>());
      for (const auto& reg : s["regions"]) {
        const int id = reg["id"];
        ASSERT_GT(region_n[id], 0);
        const double want = region_sum[id] / region_n[id];
        EXPECT_NEAR(reg["relmse"].get<double>(), want, 1e-6 * want + 1e-12) << s["strategy"] << " region " << id;
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

}  // namespace
