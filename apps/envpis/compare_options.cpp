// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <system_error>

#include "report.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using namespace envpis::render;

std::vector<Strategy> parse_strategy_list(const std::string& list) {
  std::vector<Strategy> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    item.erase(std::remove_if(item.begin(), item.end(), [](unsigned char c) { return std::isspace(c); }), item.end());
    if (item.empty()) throw Error("--strategies: empty name in '" + list + "'");
    Strategy s;
    try {
      s = parse_strategy(item);
    } catch (const std::exception&) {
      throw Error("--strategies: unknown strategy '" + item + "' (bsdf, env, mis, mis-comp, product, oracle)");
    }
    if (std::find(out.begin(), out.end(), s) != out.end())
      throw Error("--strategies: '" + item + "' is listed twice");
    out.push_back(s);
  }
  if (out.empty()) throw Error("--strategies must name at least one strategy");
  return out;
}

/// --ref-spp, --ref-strategy, --seed, --seeds, --ref-seed, --repeats.
void parse_counts_and_seeds(const CompareArgs& a, CompareSettings& s) {
  s.spp = static_cast<int>(parse_integer("--spp", a.spp, 1, kMaxSpp));
  s.ref_spp = static_cast<int>(parse_integer("--ref-spp", a.ref_spp, 1, kMaxSpp));
  if (s.ref_spp < s.spp) throw Error("--ref-spp (" + a.ref_spp + ") must be at least --spp (" + a.spp + ")");
  try {
    s.ref_strategy = parse_strategy(a.ref_strategy);
  } catch (const std::exception&) {
    throw Error("--ref-strategy: unknown strategy '" + a.ref_strategy + "'");
  }
  s.seed = static_cast<std::uint64_t>(parse_integer("--seed", a.seed, 0, INT64_MAX / 2));
  s.nseeds = static_cast<int>(parse_integer("--seeds", a.seeds, 1, kMaxSeeds));
  s.ref_seed = a.ref_seed.empty() ? s.seed + kRefSeedOffset
                                  : static_cast<std::uint64_t>(parse_integer("--ref-seed", a.ref_seed, 0, INT64_MAX));
  if (s.ref_seed >= s.seed && s.ref_seed - s.seed < static_cast<std::uint64_t>(s.nseeds))
    throw Error("--ref-seed " + std::to_string(s.ref_seed) + " is one of the measured seeds " + std::to_string(s.seed) +
                ".." + std::to_string(s.seed + s.nseeds - 1) +
                " (--seed, --seeds): the reference's noise must be independent");
  s.repeats = static_cast<int>(parse_integer("--repeats", a.repeats, 1, 100));
}

void parse_equal_time(const CompareArgs& a, CompareSettings& s) {
  if (a.equal_time.empty()) return;
  s.equal_time = true;
  if (a.equal_time == "auto") {
    s.equal_time_auto = true;
    return;
  }
  const double t = parse_number("--equal-time", a.equal_time);
  if (!(t > 0)) throw Error("--equal-time must be positive seconds or 'auto', got " + a.equal_time);
  s.equal_time_seconds = t;
}

void parse_firefly_log(const CompareArgs& a, CompareSettings& s) {
  if (!a.firefly_factor.empty()) {
    if (a.firefly_log.empty()) throw Error("--firefly-factor needs --firefly-log");
    s.firefly_factor = parse_number_in("--firefly-factor", a.firefly_factor, 0, 1e30, "> 0");
    if (!(s.firefly_factor > 0)) throw Error("--firefly-factor: must be > 0, got '" + a.firefly_factor + "'");
  }
  if (a.firefly_log.empty()) return;
  std::error_code ec;
  if (fs::exists(a.firefly_log, ec) && !fs::is_directory(a.firefly_log, ec))
    throw Error("--firefly-log '" + a.firefly_log + "' exists and is not a directory");
  fs::create_directories(a.firefly_log, ec);
  if (ec) throw Error("cannot create --firefly-log '" + a.firefly_log + "': " + ec.message());
  check_writable_file((fs::path(a.firefly_log) / "fireflies-mis.csv").string(), "--firefly-log");
  s.firefly_log = a.firefly_log;
}

void parse_analysis(const CompareArgs& a, CompareSettings& s) {
  if (a.no_analysis) {
    if (!a.analysis_points.empty()) throw Error("--analysis-points cannot be combined with --no-analysis");
    s.analysis_points = 0;
    return;
  }
  if (!a.analysis_points.empty())
    s.analysis_points = static_cast<int>(parse_integer("--analysis-points", a.analysis_points, 1, kMaxAnalysisPoints));
}

/// Creates --out and --out/images, and checks that a file can be written there.
void prepare_out(const std::string& dir) {
  if (dir.empty()) throw Error("--out is required (the output directory)");
  const fs::path out(dir);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) throw Error("--out '" + dir + "' exists and is not a directory");
  fs::create_directories(out / "images", ec);
  if (ec) throw Error("cannot create --out '" + dir + "': " + ec.message());
  const fs::path probe = out / ".envpis-write-test";
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw Error("cannot write into --out '" + dir + "': " + std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

}  // namespace

CompareSettings parse_compare_args(const CompareArgs& a) {
  CompareSettings s;
  s.strategies = parse_strategy_list(a.strategies);
  a.common.apply(s.base);
  s.base.width = static_cast<int>(parse_integer("--width", a.width, 0, kMaxImageSide));
  s.base.height = static_cast<int>(parse_integer("--height", a.height, 0, kMaxImageSide));
  a.common.map_options();
  parse_counts_and_seeds(a, s);
  parse_equal_time(a, s);
  {
    RenderOptions check = s.base;
    check.spp = s.ref_spp;
    validate(check);
  }
  parse_analysis(a, s);
  parse_firefly_log(a, s);
  prepare_out(a.out);
  s.out = a.out;
  s.report_dir = find_report_dir(a.report_dir);
  return s;
}

std::string command_line(const CLI::App& sub) {
  std::string cmd = "envpis compare";
  for (const CLI::Option* o : sub.get_options()) {
    if (o->count() == 0 || o->get_name() == "--help") continue;
    cmd += " " + o->get_name();
    if (o->get_expected_min() > 0)
      for (const auto& r : o->results()) cmd += " " + r;
  }
  return cmd;
}

void add_compare_options(CLI::App& sub, CompareArgs& a) {
  a.common.add_scene_options(sub);
  sub.add_option("--strategies", a.strategies, "comma-separated strategies to measure")
      ->type_name("LIST")
      ->capture_default_str();
  sub.add_option("--spp", a.spp, "samples per pixel of the equal-spp comparison")->type_name("INT")->capture_default_str();
  sub.add_option("--ref-spp", a.ref_spp, "samples per pixel of the reference")->type_name("INT")->capture_default_str();
  sub.add_option("--ref-strategy", a.ref_strategy, "strategy of the reference (rendered with another seed)")
      ->type_name("S")
      ->capture_default_str();
  sub.add_option("--ref-seed", a.ref_seed, "seed of the reference (default: --seed + 1000003)")->type_name("INT");
  sub.add_option("--equal-time", a.equal_time,
                 "also compare at equal time: seconds of sampling per strategy, or 'auto' (mis's time at --spp)")
      ->type_name("SECONDS|auto");
  sub.add_option("--width", a.width, "image width (0: from --height and the scene's aspect, or half the scene's)")
      ->type_name("INT")
      ->capture_default_str();
  sub.add_option("--height", a.height, "image height (0: from --width and the scene's aspect, or half the scene's)")
      ->type_name("INT")
      ->capture_default_str();
  sub.add_option("--seed", a.seed, "random seed of the measured renders")->type_name("INT")->capture_default_str();
  sub.add_option("--seeds", a.seeds,
                 "renders per strategy, seeds --seed, --seed + 1, ...: relMSE and the tail are "
                 "medians over them, 1..64")
      ->type_name("K")
      ->capture_default_str();
  sub.add_option("--repeats", a.repeats, "timing repeats of each equal-spp render under 2 s (minimum kept)")
      ->type_name("INT")
      ->capture_default_str();
  a.common.add_sampling_options(sub);
  sub.add_option("--cache-dir", a.cache_dir,
                 "reference cache (default: $ENVPIS_CACHE_DIR or ~/.cache/envpis/references)")
      ->type_name("DIR");
  sub.add_flag("--no-cache", a.no_cache, "always render the reference; do not cache it");
  sub.add_flag("--no-convergence", a.no_convergence, "skip the convergence series");
  sub.add_flag("--no-plots", a.no_plots, "do not run report/plots.py");
  sub.add_option("--analysis-points", a.analysis_points,
                 "exact variance analysis (docs/analyzer.md): shading points per object, 1.." +
                     std::to_string(kMaxAnalysisPoints) + " (default " + std::to_string(kAnalysisPoints) + ")")
      ->type_name("INT");
  sub.add_flag("--no-analysis", a.no_analysis, "skip the exact variance analysis");
  sub.add_option("--report-dir", a.report_dir, "directory of template.html, report.js, plots.py")->type_name("DIR");
  sub.add_option("--out", a.out, "output directory (metrics.json, images/, index.html)")->type_name("DIR");
  sub.add_option("--firefly-log", a.firefly_log,
                 "write DIR/fireflies-STRATEGY.csv: the samples of each equal-spp render "
                 "(first seed) whose contribution / spp exceeds --firefly-factor times "
                 "the reference pixel (docs/fireflies.md)")
      ->type_name("DIR");
  sub.add_option("--firefly-factor", a.firefly_factor,
                 "firefly log: F in contribution / spp > F sqrt(R^2 + 0.01) (default 10)")
      ->type_name("F");
  sub.add_flag("--quiet", a.quiet, "no progress lines");
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
