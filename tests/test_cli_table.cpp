// SPDX-License-Identifier: Apache-2.0
// `envpis table` end to end: runs the built command on a blender-data map and on bad inputs, and checks
// exit codes, one-line error messages, and the pictures and summary.json it writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <vector>

#include "cli_util.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using envpis::test::CmdResult;
const std::string& kBinary = envpis::test::envpis_binary();

std::string quote(const std::string& s) { return envpis::test::shell_quote(s); }

// Runs `envpis table ARGS` for every entry, several at a time.
std::vector<CmdResult> run_tables(const std::vector<std::string>& args) {
  std::vector<std::string> full;
  for (const std::string& a : args) full.push_back("table " + a);
  return envpis::test::run_envpis_all(full);
}

CmdResult run_table(const std::string& args) { return run_tables({args})[0]; }

// Every error is a single line "envpis table: error: ..." (warnings may precede it).
std::string error_line(const CmdResult& r) {
  const auto at = r.output.find("envpis table: error: ");
  if (at == std::string::npos) return {};
  return r.output.substr(at);
}

class CliTable : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("envpis_cli_table_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  void SetUp() override {
    ASSERT_TRUE(fs::exists(kBinary)) << "the envpis command was not built: " << kBinary;
  }
  static std::string path(const std::string& name) { return (dir_ / name).string(); }
  static fs::path dir_;
};
fs::path CliTable::dir_;

void expect_png(const fs::path& p, int w, int h) {
  auto in = OIIO::ImageInput::open(p.string());
  ASSERT_TRUE(in) << p << ": " << OIIO::geterror();
  EXPECT_EQ(in->spec().width, w) << p;
  EXPECT_EQ(in->spec().height, h) << p;
  EXPECT_EQ(in->spec().nchannels, 3) << p;
}

TEST_F(CliTable, SunsetWritesPicturesAndSummary) {
  if (!envpis::test::have_blender_maps()) GTEST_SKIP() << "blender-data maps not installed";
  const std::string out = path("sunset");
  const CmdResult r = run_table("--env " + quote(envpis::test::blender_map("sunset")) + " --out " + quote(out) +
                          " --normal 0,0,1 --wo 1,0,1 --proxy diffuse=0.3,reflection=0.7,alpha_r=0.3 --seed 7");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("1024x512 latlong"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("orientation panorama  filter bilinear"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("T=12 (144 top cells)  F=121  N=1452"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("build:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("memory:  table"), std::string::npos) << r.output;
  // sunset.exr has a few negative texels: the repair is reported on stderr.
  EXPECT_NE(r.output.find("warning:"), std::string::npos) << r.output;

  expect_png(fs::path(out) / "map.png", 1024, 512);
  expect_png(fs::path(out) / "importance.png", 1452, 1452);
  expect_png(fs::path(out) / "top_level.png", 768, 768);
  expect_png(fs::path(out) / "product_weights.png", 768, 768);
  expect_png(fs::path(out) / "product_samples.png", 1452, 1452);

  std::ifstream f(fs::path(out) / "summary.json");
  ASSERT_TRUE(f.good());
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["map"]["width"], 1024);
  EXPECT_EQ(j["map"]["layout"], "latlong");
  EXPECT_EQ(j["map"]["orientation"], "panorama");
  EXPECT_EQ(j["map"]["filter"], "bilinear");
  EXPECT_EQ(j["table"]["top_resolution"], 12);
  EXPECT_EQ(j["table"]["fine_resolution"], 1452);
  EXPECT_GT(j["table"]["build_seconds"].get<double>(), 0.0);
  EXPECT_GT(j["table"]["bytes_used"].get<double>(), 0.0);
  // O(T^2) overhead at most over a single-level 2D CDF.
  EXPECT_LE(j["table"]["bytes_used"].get<double>(), j["table"]["single_level_bytes"].get<double>() + 144 * 64);
  EXPECT_GT(j["map"]["repaired"]["negative"].get<int>(), 0);
  EXPECT_EQ(j["samples"]["count"], 1000);
  EXPECT_EQ(j["samples"]["zero_pdf"], 0);
  EXPECT_LT(j["samples"]["max_pdf_relative_error"].get<double>(), 1e-4);
  const auto env = j["cells"]["environment_probability"].get<std::vector<double>>();
  const auto prod = j["cells"]["product_probability"].get<std::vector<double>>();
  const auto hits = j["cells"]["samples"].get<std::vector<long long>>();
  ASSERT_EQ(env.size(), 144u);
  ASSERT_EQ(prod.size(), 144u);
  ASSERT_EQ(hits.size(), 144u);
  EXPECT_NEAR(std::accumulate(env.begin(), env.end(), 0.0), 1.0, 1e-4);
  EXPECT_NEAR(std::accumulate(prod.begin(), prod.end(), 0.0), 1.0, 1e-4);
  EXPECT_EQ(std::accumulate(hits.begin(), hits.end(), 0LL), 1000);
  // Samples land only in cells of positive product probability.
  for (int c = 0; c < 144; ++c)
    if (prod[c] == 0) EXPECT_EQ(hits[c], 0) << "cell " << c;
}

// --env-orientation and --env-filter reach the map: the output and summary.json name them.
TEST_F(CliTable, OrientationAndFilterOptions) {
  if (!envpis::test::have_blender_maps()) GTEST_SKIP() << "blender-data maps not installed";
  const std::string out = path("legacy");
  const CmdResult r = run_table("--env " + quote(envpis::test::blender_map("studio")) + " --out " + quote(out) +
                                " --fine 48 --samples 10 --env-orientation legacy --env-filter nearest");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("orientation legacy  filter nearest"), std::string::npos) << r.output;
  std::ifstream f(fs::path(out) / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["map"]["orientation"], "legacy");
  EXPECT_EQ(j["map"]["filter"], "nearest");
}

struct ErrorCase {
  std::string args;    // arguments after `envpis table`
  std::string expect;  // substring of the one error line
};

// Runs every case at once and checks: exit code 1, the expected text on a single error line.
void expect_errors(const std::vector<ErrorCase>& cases) {
  std::vector<std::string> args;
  for (const auto& c : cases) args.push_back(c.args);
  const std::vector<CmdResult> results = run_tables(args);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const CmdResult& r = results[i];
    EXPECT_EQ(r.code, 1) << cases[i].args << "\n" << r.output;
    const std::string e = error_line(r);
    EXPECT_NE(e.find(cases[i].expect), std::string::npos) << cases[i].args << "\n" << r.output;
    EXPECT_EQ(e.find('\n'), e.size() - 1) << cases[i].args << ": not one line:\n" << r.output;
  }
}

// Missing, zero-byte, non-image and directory --env: the library's message naming file and reason.
TEST_F(CliTable, BadEnvFiles) {
  const std::string missing = path("does-not-exist.exr"), empty = path("empty.exr"), text = path("text.exr"),
                    dir = path("a-directory.exr");
  std::ofstream(empty).close();
  std::ofstream(text) << "this is not an image\n";
  fs::create_directories(dir);
  const std::string out = " --out " + quote(path("o1"));
  expect_errors({
      {"--env " + quote(missing) + out, "cannot load environment map '" + missing + "': no such file"},
      {"--env " + quote(empty) + out, "cannot load environment map '" + empty + "': the file is empty"},
      {"--env " + quote(text) + out, "cannot load environment map '" + text + "'"},
      {"--env " + quote(dir) + out, "cannot load environment map '" + dir + "': is a directory"},
  });
  EXPECT_FALSE(fs::exists(path("o1") + "/summary.json"));
}

// Option errors are caught before the map is read (and before the table is built).
TEST_F(CliTable, BadOptions) {
  const std::string map = quote(envpis::test::blender_map("sunset"));
  const std::string env = " --env " + map + " --out " + quote(path("o2"));
  const std::string file = path("plain-file");
  std::ofstream(file) << "x";
  expect_errors({
      {"--top 0" + env, "--top: must be in 1..256, got '0'"},
      {"--top 12x" + env, "--top: expected an integer"},
      {"--peak-ratio 0.5" + env, "--peak-ratio: must be 0 (off) or in [1, 1e6]"},
      {"--peak-ratio -1" + env, "--peak-ratio"},
      {"--normal 0,0,0" + env, "--normal: the vector must be non-zero"},
      {"--normal 1,2" + env, "--normal: expected three comma-separated"},
      {"--normal nan,0,1" + env, "--normal: expected three comma-separated finite numbers"},
      {"--wo 0,0,0" + env, "--wo: the vector must be non-zero"},
      {"--samples 0" + env, "--samples: must be in 1.."},
      {"--proxy shiny=1" + env, "--proxy: unknown key 'shiny'"},
      {"--proxy reflection" + env, "--proxy: expected key=value"},
      {"--proxy alpha_r=1.5" + env, "--proxy alpha_r: must be in [0, 1]"},
      {"--transform fancy" + env, "--transform: unknown roughness transform 'fancy'"},
      {"--layout cube" + env, "--layout: unknown map layout 'cube'"},
      {"--env-orientation mirrored" + env, "--env-orientation: unknown lat-long orientation 'mirrored'"},
      {"--env-filter cubic" + env, "--env-filter: unknown map filter 'cubic'"},
      {"--scale -1" + env, "--scale: must be >= 0"},
      {"--out " + quote(path("o3")), "--env FILE is required"},
      {"--env " + map, "--out DIR is required"},
      {"--env " + map + " --out " + quote(file + "/sub"), "cannot create output directory '" + file + "/sub'"},
  });
  EXPECT_FALSE(fs::exists(path("o2") + "/summary.json"));
}

TEST_F(CliTable, BlackMapFailsClearly) {
  if (!envpis::test::have_blender_maps()) GTEST_SKIP() << "blender-data maps not installed";
  const CmdResult r = run_table("--env " + quote(envpis::test::blender_map("studio")) + " --scale 0 --fine 48 --out " +
                          quote(path("black")));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(error_line(r).find("no positive radiance"), std::string::npos) << r.output;
}

}  // namespace
