// SPDX-License-Identifier: Apache-2.0
// envpis analyze: the exact variance of each strategy's one-sample direct estimate at shading points of
// a scene, by quadrature (render/analyzer.h): no rendering, no Monte Carlo noise. Prints a table and
// writes every number to JSON (docs/analyzer.md).
#ifdef ENVPIS_HAVE_RENDER

#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "analysis_json.h"
#include "command.h"
#include "options.h"
#include "render/analyzer.h"
#include "render/scenes.h"

namespace envpis::app {
namespace {

using namespace envpis::render;
using json = nlohmann::json;

struct AnalyzeArgs {
  SceneOptionArgs common{"direct"};
  std::string strategies = "bsdf,env,mis,mis-comp,product,oracle";
  std::string points = "8";
  std::string refine = "4";
  std::string refine_share = "1e-4";
  std::string refine_tolerance = "1e-7";
  std::string exact = "12,24,48";
  std::string seed = "0";
  std::string json_out;
  bool visibility = false;
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

AnalyzerOptions parse_options(const AnalyzeArgs& a, int* threads) {
  RenderOptions ro;
  a.common.apply(ro);
  *threads = ro.threads;
  AnalyzerOptions o;
  o.strategies.clear();
  for (const std::string& s : split_list(a.strategies)) {
    const Strategy st = with_option("--strategies", [&] { return parse_strategy(s); });
    if (uses_portals(st))  // the analyzer's shading points carry no position for a PortalView yet
      throw Error("--strategies: the analyzer has no portal strategies yet ('" + s + "')");
    if (std::find(o.strategies.begin(), o.strategies.end(), st) == o.strategies.end()) o.strategies.push_back(st);
  }
  if (o.strategies.empty()) throw Error("--strategies: expected a comma-separated list of strategies, got '" + a.strategies + "'");
  o.heuristic = ro.heuristic;
  o.visibility = a.visibility;
  o.refine = static_cast<int>(parse_integer("--refine", a.refine, 1, 64));
  o.refine_share = parse_number_in("--refine-share", a.refine_share, 1e-12, 1, "in [1e-12, 1]");
  o.refine_tolerance = parse_number_in("--refine-tolerance", a.refine_tolerance, 1e-12, 1, "in [1e-12, 1]");
  o.exact_levels.clear();
  for (const std::string& t : split_list(a.exact))
    o.exact_levels.push_back(static_cast<int>(parse_integer("--exact", t, 1, 1024)));
  o.oracle = ro.oracle;
  o.product = ro.product;
  o.product_compensation = ro.product_compensation;
  o.light_table = ro.light_table;
  validate(o);
  return o;
}

// The header and one row per object of the renderer's estimator's V per strategy, `v` one of
// ObjectAnalysis's per-strategy summaries.
void print_estimator_rows(const Scene& scene, const SceneAnalysis& a, const AnalyzerOptions& o,
                          std::vector<double> ObjectAnalysis::*v) {
  std::printf("%-16s %4s", "object", "pts");
  for (Strategy s : o.strategies) std::printf(" %10s", to_string(s));
  std::printf("\n");
  for (const ObjectAnalysis& r : a.objects) {
    std::printf("%-16.16s %4zu", scene.objects()[r.object].name.c_str(), r.points.size());
    for (double x : r.*v) std::printf(" %10.4g", x);
    std::printf("\n");
  }
}

void print_table(const Scene& scene, const SceneAnalysis& a, const AnalyzerOptions& o) {
  std::printf("\nV = Var / I^2 of one sample, geometric mean over the points. Renderer's estimator (light + BSDF "
              "sample, %s heuristic):\n",
              to_string(o.heuristic));
  print_estimator_rows(scene, a, o, &ObjectAnalysis::v);
  // The geometric mean is the typical point's V; a relMSE over pixels averages like the arithmetic mean,
  // which the few points with a bright source in the lobe decide (docs/decisions.md, "Narrow lobes").
  std::printf("\nThe same, arithmetic mean over the points (as a relMSE averages its pixels):\n");
  print_estimator_rows(scene, a, o, &ObjectAnalysis::v_mean);
  std::printf("\nLight sample alone (weight 1) and the limits:\n%-16s", "object");
  for (Strategy s : o.strategies)
    if (s != Strategy::Bsdf) std::printf(" %10s", to_string(s));
  std::printf(" %10s", "product*");
  for (int t : o.exact_levels) std::printf(" %10s", ("exact-" + std::to_string(t)).c_str());
  std::printf("   env/prod prod/ex12 ex12/ex48   mis/prod\n");
  for (const ObjectAnalysis& r : a.objects) {
    std::printf("%-16.16s", scene.objects()[r.object].name.c_str());
    for (std::size_t i = 0; i < o.strategies.size(); ++i)
      if (o.strategies[i] != Strategy::Bsdf) std::printf(" %10.4g", r.v_light[i]);
    std::printf(" %10.4g", r.v_product);
    for (double v : r.v_exact) std::printf(" %10.4g", v);
    const Decomposition d = decompose(r, o);
    for (double x : {d.env_over_product, d.product_over_exact12, d.exact12_over_exact48, d.mis_over_product})
      if (std::isfinite(x)) std::printf(" %10.3g", x);
      else std::printf(" %10s", "-");
    std::printf("\n");
  }
  std::printf("(product*: sampling exactly proportional to BSDF x cos x environment, without visibility)\n");
}

void run(const AnalyzeArgs& a) {
  int threads = 0;
  const AnalyzerOptions o = parse_options(a, &threads);
  const int per_object = static_cast<int>(parse_integer("--points", a.points, 1, 100000));
  const std::uint64_t seed = static_cast<std::uint64_t>(parse_integer("--seed", a.seed, 0, INT64_MAX));
  if (!a.json_out.empty()) check_writable_file(a.json_out, "--json");

  std::shared_ptr<const EnvironmentMap> env;
  const Scene scene = a.common.load_scene("analyze", &env);
  if (scene.environment().is_black()) throw Error("the environment has no positive radiance: nothing to analyze");

  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  std::unique_ptr<Analyzer> analyzer;
  SceneAnalysis result;
  arena.execute([&] {
    analyzer = std::make_unique<Analyzer>(scene, o);
    result = analyze_scene(*analyzer, scene, per_object, seed);
  });

  std::printf("scene        %s, environment %s\n", a.common.scene.c_str(), scene.environment_description().c_str());
  std::printf("points       %zu analyzed (up to %d per object; %zu with no light skipped), visibility %s\n",
              result.analyzed, per_object, result.skipped, o.visibility ? "traced" : "off");
  std::printf("quadrature   %d x %d texels, refined %d x %d above share %g or error %g: %.3g directions\n",
              analyzer->grid_resolution(), analyzer->grid_resolution(), o.refine, o.refine, o.refine_share,
              o.refine_tolerance, double(result.evaluations));
  std::printf("seconds      %.2f (tables %.2f)\n", result.seconds + analyzer->build_seconds(), analyzer->build_seconds());
  print_table(scene, result, o);

  if (a.json_out.empty()) return;
  json j = analysis_json(scene, *analyzer, result);
  j["scene"] = a.common.scene;
  j["environment"] = scene.environment_description();
  std::ofstream f(a.json_out);
  f << j.dump(1) << "\n";
  if (!f) throw Error("cannot write --json '" + a.json_out + "'");
  std::printf("wrote        %s\n", a.json_out.c_str());
}

const RegisterCommand reg{{"analyze",
                           "Exact variance of each strategy's one-sample direct estimate at a scene's shading "
                           "points, by quadrature (no rendering)",
                           [](CLI::App& sub) {
                             auto a = std::make_shared<AnalyzeArgs>();
                             a->common.add_scene_options(sub);
                             sub.add_option("--strategies", a->strategies, "comma-separated strategies")
                                 ->type_name("LIST")
                                 ->capture_default_str();
                             sub.add_option("--points", a->points, "shading points per object (first hits of camera rays)")
                                 ->type_name("INT")
                                 ->capture_default_str();
                             sub.add_flag("--visibility", a->visibility,
                                          "trace every quadrature direction (default: no occlusion)");
                             sub.add_option("--refine", a->refine, "points per side in refined texels, 1..64 (1: none)")
                                 ->type_name("INT")
                                 ->capture_default_str();
                             sub.add_option("--refine-share", a->refine_share,
                                            "refine texels carrying more than this share of an integral")
                                 ->type_name("X")
                                 ->capture_default_str();
                             sub.add_option("--refine-tolerance", a->refine_tolerance,
                                            "refine texels whose estimated midpoint error exceeds this share of an "
                                            "integral")
                                 ->type_name("X")
                                 ->capture_default_str();
                             sub.add_option("--exact", a->exact, "T of the exact-T limits, comma-separated")
                                 ->type_name("LIST")
                                 ->capture_default_str();
                             sub.add_option("--seed", a->seed, "seed of the oracle's per-point jitter")
                                 ->type_name("INT")
                                 ->capture_default_str();
                             a->common.add_sampling_options(sub);
                             // The analyzer models the direct integrator and integrates exactly: no
                             // paths, no random numbers, nothing to regularize.
                             for (const char* name : {"--integrator", "--sampler", "--max-depth", "--clamp-direct",
                                                      "--clamp-indirect", "--caustics", "--filter-glossy"})
                               sub.remove_option(sub.get_option(name));
                             sub.add_option("--json", a->json_out, "write every number to this JSON file")
                                 ->type_name("FILE.json");
                             sub.callback([a] { run(*a); });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
