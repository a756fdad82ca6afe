// SPDX-License-Identifier: Apache-2.0
// The options of `envpis compare`: as typed (CompareArgs, registered on the subcommand) and checked
// (CompareSettings). Every check runs before anything slow, and every error is one line naming its
// option.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <CLI/CLI.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "options.h"

namespace envpis::app {

/// The reference's seed is --seed plus this, so its noise is independent of every measured image's.
constexpr std::uint64_t kRefSeedOffset = 1000003;
constexpr int kMaxSeeds = 64;
/// --firefly-factor's default: at 10, one logged sample alone takes its pixel about 10x off.
constexpr double kFireflyFactor = 10;
/// --analysis-points' default: shading points per object of the exact variance analysis (about 0.6 s
/// of CPU each on a 1024 x 512 map; docs/analyzer.md, "In the compare report").
constexpr int kAnalysisPoints = 2;
constexpr int kMaxAnalysisPoints = 10000;

struct CompareArgs {
  SceneOptionArgs common{"direct"};
  std::string strategies = "mis,mis-comp,product,oracle";
  std::string spp = "16";
  std::string ref_spp = "1024";
  std::string ref_strategy = "mis";
  std::string ref_seed;
  std::string equal_time;
  std::string width = "0", height = "0";  // 0: half the scene camera's size
  std::string seed = "0";
  std::string seeds = "1";
  std::string repeats = "3";
  std::string cache_dir;
  std::string report_dir;
  std::string out;
  std::string firefly_log, firefly_factor;  // empty: no log; the factor's default is kFireflyFactor
  std::string analysis_points;              // empty: kAnalysisPoints
  bool no_analysis = false;
  bool no_cache = false;
  bool no_convergence = false;
  bool no_plots = false;
  bool quiet = false;
};

struct CompareSettings {
  std::vector<render::Strategy> strategies;
  render::RenderOptions base;  // the sampling options; width and height as given (0: from the scene)
  int spp = 0, ref_spp = 0;
  render::Strategy ref_strategy = render::Strategy::Mis;
  std::uint64_t seed = 0, ref_seed = 0;
  int nseeds = 1;
  int repeats = 1;
  bool equal_time = false;       // compare at equal time too
  bool equal_time_auto = false;  // the budget is mis's time at equal spp
  double equal_time_seconds = 0; // the budget when given
  std::string firefly_log;       // the log's directory, created; empty: no log
  double firefly_factor = kFireflyFactor;
  int analysis_points = kAnalysisPoints;  // shading points per object of the analysis; 0: no analysis
  std::filesystem::path out;     // created, with out/images
  std::string report_dir;        // template.html, report.js, plots.py; empty when not found
};

/// Adds the compare options to `sub`, bound to `a`.
void add_compare_options(CLI::App& sub, CompareArgs& a);
/// Checks every option, creates --out (with images/) and --firefly-log, finds the report directory.
CompareSettings parse_compare_args(const CompareArgs& a);
/// "envpis compare --opt value ...": the command as parsed (CLI11 keeps no argv).
std::string command_line(const CLI::App& sub);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
