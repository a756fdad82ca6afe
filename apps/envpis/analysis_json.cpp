// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "analysis_json.h"

#include <cmath>
#include <string>

namespace envpis::app {
namespace {

using json = nlohmann::json;
using namespace envpis::render;

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// {strategy: values[i]} over the analyzed strategies.
json by_strategy(const AnalyzerOptions& o, const std::vector<double>& values) {
  json j = json::object();
  for (std::size_t i = 0; i < o.strategies.size(); ++i) j[to_string(o.strategies[i])] = finite_or_null(values[i]);
  return j;
}

/// {"T": values[l]} over the exact levels.
json by_level(const AnalyzerOptions& o, const std::vector<double>& values) {
  json j = json::object();
  for (std::size_t l = 0; l < o.exact_levels.size(); ++l)
    j[std::to_string(o.exact_levels[l])] = finite_or_null(values[l]);
  return j;
}

json point_json(const ShadingPointRef& ref, const PointAnalysis& p, const AnalyzerOptions& o) {
  return {{"pixel", {ref.pixel_x, ref.pixel_y}},
          {"integral", {p.integral[0], p.integral[1], p.integral[2]}},
          {"evaluations", p.evaluations},
          {"v", by_strategy(o, p.v)},
          {"v_light", by_strategy(o, p.v_light)},
          {"bias", by_strategy(o, p.bias)},
          {"v_product_limit", finite_or_null(p.v_product)},
          {"v_exact", by_level(o, p.v_exact)}};
}

json object_json(const Scene& scene, const ObjectAnalysis& r, const AnalyzerOptions& o) {
  const ObjectInfo& info = scene.objects()[static_cast<std::size_t>(r.object)];
  const Decomposition d = decompose(r, o);
  json j = {{"object", r.object},
            {"name", info.name},
            {"material", scene.material(info.material).name},
            {"points", r.points.size()},
            {"v", by_strategy(o, r.v)},
            {"v_mean", by_strategy(o, r.v_mean)},
            {"v_light", by_strategy(o, r.v_light)},
            {"v_product_limit", finite_or_null(r.v_product)},
            {"v_exact", by_level(o, r.v_exact)},
            {"ratios",
             {{"env_light/product_light", finite_or_null(d.env_over_product)},
              {"product_light/exact-12", finite_or_null(d.product_over_exact12)},
              {"exact-12/exact-48", finite_or_null(d.exact12_over_exact48)},
              {"mis/product", finite_or_null(d.mis_over_product)}}}};
  j["per_point"] = json::array();
  for (std::size_t p = 0; p < r.points.size(); ++p) j["per_point"].push_back(point_json(r.refs[p], r.points[p], o));
  return j;
}

}  // namespace

json analysis_json(const Scene& scene, const Analyzer& analyzer, const SceneAnalysis& a) {
  const AnalyzerOptions& o = analyzer.options();
  json j;
  j["heuristic"] = to_string(o.heuristic);
  j["visibility"] = o.visibility;
  j["grid_resolution"] = analyzer.grid_resolution();
  j["refine"] = o.refine;
  j["refine_share"] = o.refine_share;
  j["refine_tolerance"] = o.refine_tolerance;
  j["light_table"] = {{"top", o.light_table.top_resolution}, {"fine", analyzer.grid_resolution()},
                      {"peak_ratio", o.light_table.peak_ratio}};
  j["oracle"] = {{"resolution", o.oracle.resolution}, {"directions", o.oracle.directions}};
  j["points_per_object"] = a.per_object;
  j["points_analyzed"] = a.analyzed;
  j["points_skipped"] = a.skipped;
  j["evaluations"] = a.evaluations;
  j["seconds"] = a.seconds + analyzer.build_seconds();
  j["table_seconds"] = analyzer.build_seconds();
  j["strategies"] = json::array();
  for (Strategy s : o.strategies) j["strategies"].push_back(to_string(s));
  j["exact_levels"] = o.exact_levels;
  j["objects"] = json::array();
  for (const ObjectAnalysis& r : a.objects) j["objects"].push_back(object_json(scene, r, o));
  return j;
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
