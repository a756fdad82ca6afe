// SPDX-License-Identifier: Apache-2.0
// envpis compare: renders a reference and every strategy at equal samples (and at equal time), measures
// relMSE per image and per object, the overhead of product over mis and a convergence series, and
// writes DIR/metrics.json, every image (EXR + tonemapped PNG + false-colour error map) and the report
// DIR/index.html (report/template.html, report/report.js, report/report.css; plots by report/plots.py).
//
// Method (docs/cli.md, "envpis compare", Method):
//   relMSE(I, R) = mean over pixels and channels of (I - R)^2 / (R^2 + 0.01); efficiency = 1 / (relMSE * s)
//   with s the wall seconds of the sampling loop (tables are built once per strategy, before, and
//   reported apart). The reference is rendered with --ref-strategy (default mis: the paper's baseline,
//   unbiased and robust on every sphere) at --ref-spp with a DIFFERENT seed (--seed + 1000003), so its
//   noise is independent of every measured image, also of the measured mis image. Its remaining error is
//   reported as `relmse_floor` (the relMSE the reference's own variance adds to every measurement), and
//   every strategy's mean per object is z-tested against it (bias check). References are cached under
//   --cache-dir, keyed by everything that changes them (sidecar JSON next to the cached EXR).
//
//   Equal time: each strategy gets --equal-time seconds of sampling ("auto": the time mis took at
//   --spp); its equal-spp render is the calibration (seconds per spp), and the spp that fits the budget
//   is rendered. Overhead: time(product) / time(mis) at equal spp, same run, same threads, each the
//   minimum over --repeats renders (the images are deterministic; only the timing is repeated).
//   Convergence: relMSE at spp 1, 2, 4, ... and --spp, each rendered with the same seed (the renderer's
//   samples are keyed on (seed, pixel, sample), so the series is the prefix of the equal-spp render).
//   Seeds: with --seeds K every strategy is rendered K times at equal spp (and at equal time), with seeds
//   --seed ... --seed + K - 1; relMSE, efficiency and the tail (metrics.h) are the medians over the K,
//   reported with their spread. The images, timings and the convergence series are the first seed's.
//
// The steps, in their files: compare_options (1. options), compare_session (2-3. scene, size, tables,
// renders), compare_steps (4-8. reference via reference_cache, equal spp, overhead, convergence, equal
// time), compare_analysis (9. the exact variance analysis, render/analyzer.h), compare_images (10),
// compare_json (11. metrics.json), report (12. plots and index.html).
#ifdef ENVPIS_HAVE_RENDER

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "compare_analysis.h"
#include "compare_images.h"
#include "compare_json.h"
#include "compare_options.h"
#include "compare_session.h"
#include "compare_steps.h"
#include "report.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace envpis::render;

void print_set(const char* title, const MeasuredSet& set) {
  std::printf("%s\n", title);
  const Measured* mis = set.find(Strategy::Mis);
  for (const auto& m : set.measured) {
    const double rel = headline_relmse(m);
    const double eff = rel > 0 && m.seconds > 0 ? 1 / (rel * m.seconds) : 0;
    std::printf("%-9s %8d %9.3f %11.4g %11.4g", to_string(m.strategy), m.spp, m.seconds, rel, eff);
    if (mis && rel > 0)
      std::printf(" %8.2fx", headline_relmse(*mis) / rel);
    else
      std::printf(" %9s", "-");
    std::printf(" %11.4g %8g %11.4g\n",
                median(over_seeds(m, [](const ImageMetrics& x) { return x.image.max_rel_sq_error; })),
                median(over_seeds(m, [](const ImageMetrics& x) { return x.image.pixels_over_10x; })),
                median(over_seeds(m, [](const ImageMetrics& x) { return x.image.relmse_trimmed; })));
  }
}

// 13. The summary on stdout.
void print_summary(const CompareSession& session, const Comparison& c) {
  if (session.settings.nseeds > 1)
    std::printf("(relMSE, efficiency and the tail: medians over %d seeds)\n", session.settings.nseeds);
  std::printf("%-9s %8s %9s %11s %11s %9s %11s %8s %11s\n", "strategy", "spp", "seconds", "relMSE", "efficiency",
              "vs mis", "max rel.e", ">10x px", "trimmed");
  print_set("equal spp:", c.equal_spp);
  if (!c.equal_time.measured.empty()) print_set("equal time:", c.equal_time);
  if (!c.overhead.is_null())
    std::printf("overhead  time(product)/time(mis) = %.3f (wall), %.3f (CPU)\n", c.overhead["ratio"].get<double>(),
                c.overhead["ratio_cpu"].is_null() ? 0.0 : c.overhead["ratio_cpu"].get<double>());
  if (c.analysis.is_object())
    std::printf("analysis  exact V of one sample at %zu shading points (%d per object): metrics.json \"analysis\", "
                "the report's table\n",
                c.analysis["points_analyzed"].get<std::size_t>(), session.settings.analysis_points);
  const fs::path index = session.settings.out / "index.html";
  std::error_code ec;
  const fs::path abs = fs::absolute(index, ec);
  std::printf("report    %s\n", (ec ? index : abs).c_str());
}

// 11-12. metrics.json, the plots (whose manifest joins metrics.json) and index.html.
void write_results(const CompareSession& session, const Comparison& c, const std::string& command_line,
                   double exposure) {
  const fs::path out = session.settings.out;
  json j = metrics_json(session, c, command_line, exposure);
  const fs::path metrics_path = out / "metrics.json";
  auto write_metrics = [&] { std::ofstream(metrics_path) << j.dump(2) << "\n"; };
  write_metrics();
  add_plots(j, metrics_path, session.settings.report_dir, session.args.no_plots, "compare");
  write_metrics();
  std::vector<FallbackImage> fallback{{"", "images/reference.png", "reference"}};
  for (const auto& m : c.equal_spp.measured)
    fallback.push_back({to_string(m.strategy), "images/" + m.stem + ".png", to_string(m.strategy)});
  const std::string title = "envpis compare: " + session.args.common.scene + " under " +
                            fs::path(j["environment"].get<std::string>()).filename().string();
  write_report_html(out, session.settings.report_dir, title, j, fallback, "compare");
}

void run(const CompareArgs& a, const std::string& command_line) {
  // 1. Options, all checked before anything slow.
  const CompareSettings settings = parse_compare_args(a);
  Progress progress(a.quiet);
  // 2. Scene and environment.
  const Scene scene = a.common.load_scene("compare", nullptr);
  if (!scene.has_environment() || scene.environment().is_black())
    throw Error("the environment (" + scene.environment_description() +
                ") has no positive radiance: every strategy renders a black image, there is nothing to compare");
  // 3. The renders' shared state; tables are built once per strategy, on first use.
  CompareSession session(a, settings, scene, progress);
  progress.line("scene %s, %dx%d, environment %s, integrator %s, sampler %s, %d threads", a.common.scene.c_str(),
                session.width, session.height, scene.environment_description().c_str(),
                to_string(session.base.integrator), to_string(session.base.sampler), session.threads_used);
  // 4-8. The measurements.
  Comparison c;
  obtain_reference(session, c);
  measure_equal_spp(session, c);
  measure_overhead(session, c);
  if (!a.no_convergence) measure_convergence(session, c);
  if (settings.equal_time) measure_equal_time(session, c);
  // 9. The exact variance analysis.
  analyze_shading_points(session, c);
  // 10. Images.
  const double exposure = tonemap_exposure(c.reference);
  write_images(session, c, exposure);
  // 11-12. metrics.json, plots, report.
  write_results(session, c, command_line, exposure);
  // 13. Summary.
  print_summary(session, c);
  progress.line("done");
}

const RegisterCommand reg{{"compare",
                           "Compare sampling strategies against a reference: metrics.json, images and an HTML report",
                           [](CLI::App& sub) {
                             auto a = std::make_shared<CompareArgs>();
                             add_compare_options(sub, *a);
                             sub.callback([a, &sub] { run(*a, command_line(sub)); });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
