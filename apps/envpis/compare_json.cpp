// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_json.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <thread>

#include "compare_images.h"
#include "picture.h"

namespace envpis::app {
namespace {

using json = nlohmann::json;
using namespace envpis::render;

json num(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }
/// A pixel count, or the median of an even number of counts (which may end in .5).
json count_json(double x) { return x == std::floor(x) ? json(static_cast<std::uint64_t>(x)) : json(x); }

/// Writes NAME = the median of `v` (one value per seed), NAME_seeds = `v`, and the spread: NAME_min and
/// NAME_max, or for a tail metric only NAME_worst (the largest).
void put_over_seeds(json& j, const std::string& name, const std::vector<double>& v, json (*as)(double), bool spread) {
  j[name] = as(median(v));
  json list = json::array();
  for (double x : v) list.push_back(as(x));
  j[name + "_seeds"] = list;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  if (spread) j[name + "_min"] = as(*lo);
  j[name + (spread ? "_max" : "_worst")] = as(*hi);
}

/// relMSE and the tail of one set of pixels (`region` of the regions, or the image for `npos`) over the
/// seeds: relmse (= relmse_median), relmse_seeds, relmse_min, relmse_max, max_rel_sq_error(_seeds,
/// _worst), pixels_over_10x(_seeds, _worst).
void put_seed_statistics(json& j, const Measured& m, std::size_t region) {
  auto set = [region](const ImageMetrics& x) -> const PixelSetMetrics& {
    return region == std::string::npos ? x.image : x.regions[region];
  };
  const std::vector<double> relmse = over_seeds(m, [&](const ImageMetrics& x) { return set(x).relmse; });
  put_over_seeds(j, "relmse", relmse, num, true);
  j["relmse_median"] = j["relmse"];
  put_over_seeds(j, "max_rel_sq_error", over_seeds(m, [&](const ImageMetrics& x) { return set(x).max_rel_sq_error; }),
                 num, false);
  put_over_seeds(j, "pixels_over_10x", over_seeds(m, [&](const ImageMetrics& x) { return set(x).pixels_over_10x; }),
                 count_json, false);
  // The figures one caustic pixel cannot decide, and the light samples' share of the variance.
  put_over_seeds(j, "relmse_trimmed", over_seeds(m, [&](const ImageMetrics& x) { return set(x).relmse_trimmed; }), num,
                 true);
  put_over_seeds(j, "median_rel_sq_error",
                 over_seeds(m, [&](const ImageMetrics& x) { return set(x).median_rel_sq_error; }), num, true);
  put_over_seeds(j, "light_variance_share",
                 over_seeds(m, [&](const ImageMetrics& x) { return set(x).light_variance_share; }), num, true);
}

json set_json(const MeasuredSet& set, const std::vector<Region>& regions) {
  json arr = json::array();
  for (const Measured& m : set.measured) arr.push_back(measured_json(m, regions));
  return arr;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return buf;
}

/// What was compared, and how: the command, the scene, the image, the seeds, the integrator.
void put_run(json& j, const CompareSession& session, const std::string& command_line) {
  const CompareArgs& a = session.args;
  const CompareSettings& s = session.settings;
  const RenderOptions& base = session.base;
  j["tool"] = "envpis compare";
  j["version"] = kVersion;
  j["command"] = command_line;
  j["date"] = utc_now();
  j["scene"] = a.common.scene;
  j["environment"] = a.common.env.empty() ? session.scene.environment_description() : a.common.env;
  j["integrator"] = to_string(base.integrator);
  if (base.integrator == IntegratorKind::Path) j["max_depth"] = base.max_depth;
  j["heuristic"] = to_string(base.heuristic);
  j["sampler"] = to_string(base.sampler);
  j["width"] = session.width;
  j["height"] = session.height;
  j["seed"] = s.seed;
  j["seeds"] = json::array();
  for (int k = 0; k < s.nseeds; ++k) j["seeds"].push_back(s.seed + k);
  j["threads"] = session.threads_used;
  j["hardware_threads"] = std::thread::hardware_concurrency();
}

void put_definitions(json& j) {
  j["relmse_definition"] = "mean over pixels and channels of (I - R)^2 / (R^2 + 0.01)";
  j["efficiency_definition"] = "1 / (relmse * seconds), seconds = wall time of the sampling loop";
  j["tail_definition"] = "per-pixel relative squared error e = mean over channels of (I - R)^2 / (R^2 + 0.01); "
                         "max_rel_sq_error = the largest e; pixels_over_10x = the number of pixels with e > 100";
  j["robust_definition"] = "relmse_trimmed = the mean of e without the worst ceil(0.1%) of the pixels (at least one, "
                           "never all); median_rel_sq_error = the median of e";
  j["light_variance_share_definition"] =
      "sum over pixels of var_light / (R^2 + 0.01) over the sum of var / (R^2 + 0.01): var the variance of the "
      "pixel's mean, var_light that of the part light samples brought (at every path vertex); the covariance "
      "of the two parts is in var, so the share can exceed 1";
  j["seeds_definition"] = "each strategy is rendered once per seed in `seeds`; relmse (= relmse_median), efficiency, "
                          "max_rel_sq_error and pixels_over_10x are medians over the seeds, _min/_max/_worst their "
                          "spread, _seeds the values per seed; images, relmse_stderr, mean, z, nan_count, seconds "
                          "and convergence are the first seed's";
}

/// The sampling options: the product's, the oracle's, the light table's, the environment's transform.
void put_sampling_options(json& j, const CompareSession& session) {
  const SceneOptionArgs& common = session.args.common;
  const RenderOptions& base = session.base;
  const Scene& scene = session.scene;
  j["product_options"] = {{"proxy_transform", static_cast<int>(base.product.proxy.transform)},
                          {"proxy_lobe", to_string(base.product.proxy.reflection_lobe)},
                          {"proxy_min_alpha", base.product.proxy.min_alpha},
                          {"proxy_max_alpha", base.product.proxy.max_alpha},
                          {"env_mix", base.product.env_mix},
                          {"env_floor", base.product.env_floor},
                          {"cell_estimate", to_string(base.product.cell_estimate)},
                          {"compensation", to_string(base.product_compensation)},
                          {"max_roughness", base.product_max_roughness < render::kInfinity
                                                ? json(base.product_max_roughness)
                                                : json("inf")}};
  if (!common.proxy_transform.empty()) j["product_options"]["proxy_transform_name"] = common.proxy_transform;
  j["oracle_options"] = {{"resolution", base.oracle.resolution}, {"directions", base.oracle.directions}};
  j["top_resolution"] = base.light_table.top_resolution;
  j["fine_resolution"] = base.light_table.fine_resolution;
  j["peak_ratio"] = base.light_table.peak_ratio;
  j["closed_surfaces"] = scene.proxy_closed_surfaces();
  j["regularization"] = regularization_json(base.regularization);
  j["regularized"] = base.regularization.active();
  if (!common.env.empty())
    j["environment_transform"] = {{"rotation_degrees", parse_number("--env-rotation", common.env_rotation)},
                                  {"scale", parse_number("--env-scale", common.env_scale)}};
  if (scene.has_environment())
    j["environment_lookup"] = {{"orientation", to_string(scene.environment().orientation())},
                               {"filter", to_string(scene.environment().filter())}};
  json tj = json::object();
  for (const auto& [s, t] : session.tables()) tj[to_string(s)] = t.build_seconds;
  j["table_seconds"] = tj;
}

json reference_json(const Comparison& c) {
  const Reference& ref = c.reference;
  return {{"strategy", to_string(ref.strategy)},
          {"spp", ref.spp},
          {"seed", ref.seed},
          {"seconds", ref.seconds},
          {"cached", ref.cached},
          {"cache_dir", c.cache_dir},
          {"relmse_floor", reference_floor(NoisyImage{ref.rgb, ref.variance})},
          {"exr", "images/reference.exr"},
          {"png", "images/reference.png"},
          {"object_id_exr", "images/object-id.exr"}};
}

json region_list_json(const std::vector<Region>& regions) {
  json rj = json::array();
  for (const auto& r : regions)
    rj.push_back({{"id", r.id},
                  {"name", r.name},
                  {"pixels", r.pixels},
                  {"bbox", {r.x0, r.y0, r.x1 + 1, r.y1 + 1}},
                  {"centroid", {r.cx, r.cy}}});
  return rj;
}

json error_map_json() {
  json stops = json::array();
  for (const auto& s : inferno_stops()) stops.push_back({s[0], s[1], s[2]});
  return {{"quantity", "mean over channels of (I - R)^2 / (R^2 + 0.01)"},
          {"log10_min", kErrLog10Min},
          {"log10_max", kErrLog10Max},
          {"colormap", stops}};
}

}  // namespace

json regions_json(const std::vector<Region>& regions, const ImageMetrics& m, bool with_z) {
  json arr = json::array();
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const PixelSetMetrics& g = m.regions[i];
    json r = {{"id", regions[i].id},
              {"name", regions[i].name},
              {"relmse", num(g.relmse)},
              {"relmse_stderr", num(g.relmse_stderr)},
              {"mean", num(g.mean)}};
    if (with_z) r["z"] = num(g.z);
    arr.push_back(r);
  }
  return arr;
}

json measured_json(const Measured& x, const std::vector<Region>& regions) {
  json j;
  j["strategy"] = to_string(x.strategy);
  j["spp"] = x.spp;
  j["seconds"] = x.seconds;
  j["seconds_runs"] = x.seconds_runs;
  j["cpu_seconds"] = x.cpu_seconds;
  put_seed_statistics(j, x, std::string::npos);
  j["relmse_stderr"] = num(x.metrics.image.relmse_stderr);
  const double relmse = headline_relmse(x);
  j["efficiency"] = relmse > 0 && x.seconds > 0 ? json(1.0 / (relmse * x.seconds)) : json(nullptr);
  j["mean"] = x.metrics.image.mean;
  j["nan_count"] = x.nan_count;
  j["regions"] = regions_json(regions, x.metrics, true);
  for (std::size_t i = 0; i < regions.size(); ++i) put_seed_statistics(j["regions"][i], x, i);
  j["images"] = {{"exr", "images/" + x.stem + ".exr"},
                 {"png", "images/" + x.stem + ".png"},
                 {"error_png", "images/" + x.stem + "-error.png"}};
  return j;
}

json metrics_json(const CompareSession& session, const Comparison& c, const std::string& command_line,
                  double exposure) {
  json j;
  put_run(j, session, command_line);
  put_definitions(j);
  put_sampling_options(j, session);
  j["reference"] = reference_json(c);
  j["regions"] = region_list_json(c.regions);
  j["equal_spp"] = {{"spp", session.settings.spp}, {"strategies", set_json(c.equal_spp, c.regions)}};
  if (!c.equal_time.measured.empty())
    j["equal_time"] = {{"budget_seconds", c.budget},
                       {"budget", session.settings.equal_time_auto ? "auto (time of mis at equal spp)" : "given"},
                       {"strategies", set_json(c.equal_time, c.regions)}};
  else
    j["equal_time"] = nullptr;
  j["overhead"] = c.overhead;
  j["convergence"] = c.convergence;
  j["analysis"] = c.analysis;
  if (!c.analysis_unavailable.empty()) j["analysis_unavailable"] = c.analysis_unavailable;
  j["error_map"] = error_map_json();
  j["tonemap"] = {{"curve", "1 - exp(-k x), then sRGB"}, {"k", exposure}};
  return j;
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
