// envpis analyze: the exact variance of each strategy's one-sample direct estimate at shading points of
// a scene, by quadrature (render/analyzer.h): no rendering, no Monte Carlo noise. Prints a table and
// writes every number to JSON (docs/analyzer.md).
#ifdef ENVPIS_HAVE_RENDER

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "command.h"
#include "options.h"
#include "render/analyzer.h"
#include "render/hash.h"
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
  o.light_table = ro.light_table;
  validate(o);
  return o;
}

/// Per object: the analyses of its points.
struct ObjectResult {
  int object = -1;
  std::vector<const ShadingPointRef*> refs;
  std::vector<PointAnalysis> points;
};

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// Geometric means over an object's points of one quantity.
template <class F>
double object_mean(const ObjectResult& r, F get) {
  std::vector<double> v;
  for (const PointAnalysis& p : r.points) v.push_back(get(p));
  return geometric_mean(v);
}

struct Summary {  // one object's geometric means (and arithmetic means of v, as relMSE averages pixels)
  std::vector<double> v, v_light, v_exact, v_mean;
  double v_product = 0;
};

Summary summarize(const ObjectResult& r, const AnalyzerOptions& o) {
  Summary s;
  for (std::size_t i = 0; i < o.strategies.size(); ++i) {
    s.v.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v[i]; }));
    s.v_light.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v_light[i]; }));
    double sum = 0;
    for (const PointAnalysis& p : r.points) sum += p.v[i];
    s.v_mean.push_back(r.points.empty() ? std::nan("") : sum / double(r.points.size()));
  }
  s.v_product = object_mean(r, [](const PointAnalysis& p) { return p.v_product; });
  for (std::size_t l = 0; l < o.exact_levels.size(); ++l)
    s.v_exact.push_back(object_mean(r, [&](const PointAnalysis& p) { return p.v_exact[l]; }));
  return s;
}

int index_of(const AnalyzerOptions& o, Strategy s) {
  for (std::size_t i = 0; i < o.strategies.size(); ++i)
    if (o.strategies[i] == s) return static_cast<int>(i);
  return -1;
}
int level_index(const AnalyzerOptions& o, int t) {
  for (std::size_t i = 0; i < o.exact_levels.size(); ++i)
    if (o.exact_levels[i] == t) return static_cast<int>(i);
  return -1;
}

/// The decomposition of the issue-10 table (light samples alone) plus the MIS ratio compare measures.
json ratios(const Summary& s, const AnalyzerOptions& o) {
  json j = json::object();
  const int env = index_of(o, Strategy::Env), product = index_of(o, Strategy::Product), mis = index_of(o, Strategy::Mis);
  const int lo = level_index(o, 12), hi = level_index(o, 48);
  if (env >= 0 && product >= 0) j["env_light/product_light"] = finite_or_null(s.v_light[env] / s.v_light[product]);
  if (product >= 0 && lo >= 0) j["product_light/exact-12"] = finite_or_null(s.v_light[product] / s.v_exact[lo]);
  if (lo >= 0 && hi >= 0) j["exact-12/exact-48"] = finite_or_null(s.v_exact[lo] / s.v_exact[hi]);
  if (mis >= 0 && product >= 0) j["mis/product"] = finite_or_null(s.v[mis] / s.v[product]);
  return j;
}

json point_json(const ShadingPointRef& ref, const PointAnalysis& p, const AnalyzerOptions& o) {
  json j;
  j["pixel"] = {ref.pixel_x, ref.pixel_y};
  j["integral"] = {p.integral[0], p.integral[1], p.integral[2]};
  j["evaluations"] = p.evaluations;
  json v, vl, b, ex;
  for (std::size_t i = 0; i < o.strategies.size(); ++i) {
    v[to_string(o.strategies[i])] = finite_or_null(p.v[i]);
    vl[to_string(o.strategies[i])] = finite_or_null(p.v_light[i]);
    b[to_string(o.strategies[i])] = finite_or_null(p.bias[i]);
  }
  for (std::size_t l = 0; l < o.exact_levels.size(); ++l) ex[std::to_string(o.exact_levels[l])] = finite_or_null(p.v_exact[l]);
  j["v"] = v;
  j["v_light"] = vl;
  j["bias"] = b;
  j["v_product_limit"] = finite_or_null(p.v_product);
  j["v_exact"] = ex;
  return j;
}

void print_table(const Scene& scene, const std::vector<ObjectResult>& results, const std::vector<Summary>& sums,
                 const AnalyzerOptions& o) {
  std::printf("\nV = Var / I^2 of one sample, geometric mean over the points. Renderer's estimator (light + BSDF "
              "sample, %s heuristic):\n",
              to_string(o.heuristic));
  std::printf("%-16s %4s", "object", "pts");
  for (Strategy s : o.strategies) std::printf(" %10s", to_string(s));
  std::printf("\n");
  for (std::size_t r = 0; r < results.size(); ++r) {
    std::printf("%-16.16s %4zu", scene.objects()[results[r].object].name.c_str(), results[r].points.size());
    for (double v : sums[r].v) std::printf(" %10.4g", v);
    std::printf("\n");
  }
  std::printf("\nLight sample alone (weight 1) and the limits:\n%-16s", "object");
  for (Strategy s : o.strategies)
    if (s != Strategy::Bsdf) std::printf(" %10s", to_string(s));
  std::printf(" %10s", "product*");
  for (int t : o.exact_levels) std::printf(" %10s", ("exact-" + std::to_string(t)).c_str());
  std::printf("   env/prod prod/ex12 ex12/ex48   mis/prod\n");
  for (std::size_t r = 0; r < results.size(); ++r) {
    std::printf("%-16.16s", scene.objects()[results[r].object].name.c_str());
    for (std::size_t i = 0; i < o.strategies.size(); ++i)
      if (o.strategies[i] != Strategy::Bsdf) std::printf(" %10.4g", sums[r].v_light[i]);
    std::printf(" %10.4g", sums[r].v_product);
    for (double v : sums[r].v_exact) std::printf(" %10.4g", v);
    const json j = ratios(sums[r], o);
    for (const char* k : {"env_light/product_light", "product_light/exact-12", "exact-12/exact-48", "mis/product"})
      if (j.contains(k) && !j[k].is_null()) std::printf(" %10.3g", j[k].get<double>());
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

  const auto t0 = std::chrono::steady_clock::now();
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  std::unique_ptr<Analyzer> analyzer;
  std::vector<ShadingPointRef> refs;
  std::vector<std::optional<PointAnalysis>> out;
  arena.execute([&] {
    analyzer = std::make_unique<Analyzer>(scene, o);
    refs = first_hit_points(scene, per_object);
    out.resize(refs.size());
    tbb::parallel_for(std::size_t(0), refs.size(), [&](std::size_t i) {
      const ShadingPointRef& r = refs[i];
      out[i] = analyzer->analyze(r.ray, mix64(seed ^ mix64(std::uint64_t(r.pixel_y) * 65536 + r.pixel_x)));
    });
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::vector<ObjectResult> results;
  std::size_t skipped = 0, evaluations = 0;
  for (std::size_t i = 0; i < refs.size(); ++i) {
    if (!out[i]) {
      ++skipped;
      continue;
    }
    if (results.empty() || results.back().object != refs[i].object) results.push_back({refs[i].object, {}, {}});
    results.back().refs.push_back(&refs[i]);
    evaluations += out[i]->evaluations;
    results.back().points.push_back(std::move(*out[i]));
  }
  std::vector<Summary> sums;
  for (const ObjectResult& r : results) sums.push_back(summarize(r, o));

  std::printf("scene        %s, environment %s\n", a.common.scene.c_str(), scene.environment_description().c_str());
  std::printf("points       %zu analyzed (up to %d per object; %zu with no light skipped), visibility %s\n",
              refs.size() - skipped, per_object, skipped, o.visibility ? "traced" : "off");
  std::printf("quadrature   %d x %d texels, refined %d x %d above share %g or error %g: %.3g directions\n",
              analyzer->grid_resolution(), analyzer->grid_resolution(), o.refine, o.refine, o.refine_share,
              o.refine_tolerance, double(evaluations));
  std::printf("seconds      %.2f (tables %.2f)\n", seconds, analyzer->build_seconds());
  print_table(scene, results, sums, o);

  if (a.json_out.empty()) return;
  json j;
  j["scene"] = a.common.scene;
  j["environment"] = scene.environment_description();
  j["heuristic"] = to_string(o.heuristic);
  j["visibility"] = o.visibility;
  j["grid_resolution"] = analyzer->grid_resolution();
  j["refine"] = o.refine;
  j["refine_share"] = o.refine_share;
  j["refine_tolerance"] = o.refine_tolerance;
  j["light_table"] = {{"top", o.light_table.top_resolution}, {"fine", analyzer->grid_resolution()},
                      {"peak_ratio", o.light_table.peak_ratio}};
  j["oracle"] = {{"resolution", o.oracle.resolution}, {"directions", o.oracle.directions}};
  j["seconds"] = seconds;
  j["table_seconds"] = analyzer->build_seconds();
  j["strategies"] = json::array();
  for (Strategy s : o.strategies) j["strategies"].push_back(to_string(s));
  j["exact_levels"] = o.exact_levels;
  j["objects"] = json::array();
  for (std::size_t r = 0; r < results.size(); ++r) {
    const ObjectInfo& info = scene.objects()[results[r].object];
    json oj;
    oj["object"] = results[r].object;
    oj["name"] = info.name;
    oj["material"] = scene.material(info.material).name;
    oj["points"] = results[r].points.size();
    json v, vm, vl, ex;
    for (std::size_t i = 0; i < o.strategies.size(); ++i) {
      v[to_string(o.strategies[i])] = finite_or_null(sums[r].v[i]);
      vm[to_string(o.strategies[i])] = finite_or_null(sums[r].v_mean[i]);
      vl[to_string(o.strategies[i])] = finite_or_null(sums[r].v_light[i]);
    }
    for (std::size_t l = 0; l < o.exact_levels.size(); ++l)
      ex[std::to_string(o.exact_levels[l])] = finite_or_null(sums[r].v_exact[l]);
    oj["v"] = v;
    oj["v_mean"] = vm;
    oj["v_light"] = vl;
    oj["v_product_limit"] = finite_or_null(sums[r].v_product);
    oj["v_exact"] = ex;
    oj["ratios"] = ratios(sums[r], o);
    oj["per_point"] = json::array();
    for (std::size_t p = 0; p < results[r].points.size(); ++p)
      oj["per_point"].push_back(point_json(*results[r].refs[p], results[r].points[p], o));
    j["objects"].push_back(oj);
  }
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
                             // paths, no random numbers.
                             for (const char* name : {"--integrator", "--sampler", "--max-depth"})
                               sub.remove_option(sub.get_option(name));
                             sub.add_option("--json", a->json_out, "write every number to this JSON file")
                                 ->type_name("FILE.json");
                             sub.callback([a] { run(*a); });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
