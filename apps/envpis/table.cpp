// SPDX-License-Identifier: Apache-2.0
// envpis table: builds the importance table of an environment map, prints its figures (size, build
// time, memory) and writes pictures of it that a person can look at:
//   map.png              the environment map itself, tonemapped, in its own layout
//   importance.png       the N x N fine importance on the equal-area square (log scale, inferno colours)
//   top_level.png        the T x T top-cell probabilities E[c] (log scale) with the grid
//   product_weights.png  the T x T product probabilities P[c] / sum P for the shading point (log scale)
//   product_samples.png  the importance image darkened, with --samples product samples as yellow dots
//   summary.json         every figure printed, plus the per-cell probabilities
// On the square pictures the dashed diamond is the horizon (z = 0: upper hemisphere inside, the four
// corners are the south pole), a green + is the shading normal, and rings mark the proxy's active
// lobe axes (green: diffuse N / translucent -N, cyan: reflection R, magenta: refraction T).
// Usage and option reference: docs/cli.md.
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "command.h"
#include "envpis/envpis.h"
#include "picture.h"
#include "table_options.h"
#include "table_pictures.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Json vec_json(Vec3 v) { return Json::array({v.x, v.y, v.z}); }

std::string mib(std::size_t bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f MiB", double(bytes) / (1024.0 * 1024.0));
  return buf;
}

std::string no_radiance(const std::string& env, const char* consequence) {
  return "environment map '" + env + "' has no positive radiance (black everywhere after repair and --scale): the " +
         consequence + ", there is nothing to sample";
}

// Step 2: the map, its figures and map.png.
EnvironmentMap load_map(const TableSettings& s) {
  const EnvironmentMap map = [&] {
    try {
      return EnvironmentMap::load(s.env, s.map_options);
    } catch (const Error& e) {  // the loader's messages name the file; the layout check does not
      if (std::string(e.what()).find(s.env) != std::string::npos) throw;
      throw Error("cannot use environment map '" + s.env + "': " + e.what());
    }
  }();
  if (map.is_black()) throw Error(no_radiance(s.env, "importance table would be empty"));
  std::printf("map:     %s  %dx%d %s  scale %g  rotate %g deg  orientation %s  filter %s\n", s.env.c_str(),
              map.width(), map.height(), to_string(map.layout()), double(map.scale()), double(s.rotate_degrees),
              map.layout() == MapLayout::LatLong ? to_string(map.orientation()) : "n/a", to_string(map.filter()));
  for (const std::string& w : map.warnings()) std::fprintf(stderr, "envpis table: warning: %s\n", w.c_str());
  write_png((s.out / "map.png").string(), tonemap_map(map));
  return map;
}

// Step 3: the table's figures.
void print_table_figures(const ImportanceTable& table, int threads) {
  const int T = table.top_resolution(), N = table.fine_resolution();
  std::printf("table:   T=%d (%d top cells)  F=%d  N=%d (%lld fine texels)\n", T, T * T, table.cell_resolution(), N,
              static_cast<long long>(N) * N);
  std::printf("build:   %.4f s (%d threads)\n", table.build_seconds(), threads);
  const std::size_t bytes = table.bytes_used(), single = table.single_level_bytes();
  std::printf("memory:  table %zu bytes (%s); single-level 2D CDF over the same texels %zu bytes (%s); "
              "ratio %.4f\n",
              bytes, mib(bytes).c_str(), single, mib(single).c_str(), double(bytes) / double(single));
}

// Step 4: the product for the shading point; returns the nanoseconds of one prepare().
double prepare_product(ProductSampler& sampler, const TableSettings& s) {
  if (!sampler.prepare(s.normal, s.wo, s.proxy)) throw Error("the product sampler rejected the shading point");
  const auto t0 = std::chrono::steady_clock::now();
  const int reps = 2000;
  for (int i = 0; i < reps; ++i) sampler.prepare(s.normal, s.wo, s.proxy);
  const double prepare_ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / reps;
  const PreparedProxy& pp = sampler.prepared_proxy();
  const BsdfProxy& proxy = s.proxy;
  std::printf("shading: normal (%.4g, %.4g, %.4g)  wo (%.4g, %.4g, %.4g)\n", s.normal.x, s.normal.y, s.normal.z,
              s.wo.x, s.wo.y, s.wo.z);
  std::printf("proxy:   diffuse=%g translucent=%g reflection=%g refraction=%g alpha_r=%g alpha_t=%g ior=%g\n",
              double(proxy.diffuse), double(proxy.translucent), double(proxy.reflection), double(proxy.refraction),
              double(proxy.alpha_reflection), double(proxy.alpha_refraction), double(proxy.ior));
  std::printf("         transform %s, min-alpha %g, max-alpha %g -> alpha_r' %.4g alpha_t' %.4g eta %.4g%s\n",
              to_string(s.sampler_options.proxy.transform), double(s.sampler_options.proxy.min_alpha),
              double(s.sampler_options.proxy.max_alpha), double(pp.alpha_r), double(pp.alpha_t), double(pp.eta),
              pp.tir ? " (total internal reflection)" : "");
  if (sampler.uses_environment_fallback())
    std::fprintf(stderr,
                 "envpis table: warning: the proxy gives no cell a positive weight (all-zero proxy?): the "
                 "product sampler falls back to environment-only sampling\n");
  std::printf("product: prepare %.0f ns per shading point (%s)\n", prepare_ns, to_string(sampler.simd()));
  return prepare_ns;
}

struct SampleStats {
  std::vector<Point2> points;         // on the equal-area square
  std::vector<long long> per_cell;    // samples per top cell
  long long above = 0, rejected = 0;  // above the surface; with pdf 0
  double max_rel = 0;                 // the largest |pdf(direction) - sample pdf| / pdf
  int top_k = 0;                      // the most probable cells compared below
  double expected_top = 0, observed_top = 0;
};

// Step 5: --samples product samples, and the share in the 5 most probable cells versus their probability.
SampleStats draw_samples(const ProductSampler& sampler, const ImportanceTable& table, const TableSettings& s,
                         const std::vector<float>& prod_prob) {
  const int T = table.top_resolution();
  SampleStats st;
  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  st.points.reserve(std::size_t(s.samples));
  st.per_cell.assign(std::size_t(T) * T, 0);
  for (long long i = 0; i < s.samples; ++i) {
    Point2 u{uni(rng), uni(rng)};
    u.x = std::min(u.x, 0.99999994f);
    u.y = std::min(u.y, 0.99999994f);
    const DirectionSample d = sampler.sample(u);
    if (!(d.pdf > 0)) {
      ++st.rejected;
      continue;
    }
    const float p = sampler.pdf(d.direction);
    st.max_rel = std::max(st.max_rel, std::fabs(double(p) - d.pdf) / d.pdf);
    st.points.push_back(equal_area_sphere_to_square(d.direction));
    ++st.per_cell[std::size_t(table.cell_of_direction(d.direction))];
    if (dot(d.direction, s.normal) > 0) ++st.above;
  }
  std::vector<int> order(std::size_t(T) * T);
  for (int c = 0; c < T * T; ++c) order[c] = c;
  st.top_k = std::min(5, T * T);
  std::partial_sort(order.begin(), order.begin() + st.top_k, order.end(),
                    [&](int x, int y) { return prod_prob[x] > prod_prob[y]; });
  for (int i = 0; i < st.top_k; ++i) {
    st.expected_top += prod_prob[order[i]];
    st.observed_top += double(st.per_cell[order[i]]) / double(s.samples);
  }
  std::printf("samples: %lld (seed %llu): %.1f%% above the surface; %d most probable cells hold %.1f%% "
              "(expected %.1f%%); max |pdf(dir) - sample pdf| / pdf = %.2g%s\n",
              s.samples, s.seed, 100.0 * st.above / double(s.samples), st.top_k, 100.0 * st.observed_top,
              100.0 * st.expected_top, st.max_rel, st.rejected ? " (some samples had pdf 0!)" : "");
  return st;
}

// Step 6: importance.png, top_level.png, product_weights.png, product_samples.png.
void write_pictures(const fs::path& out, const ImportanceTable& table, const PreparedProxy& pp, Vec3 normal,
                    const std::vector<float>& env_prob, const std::vector<float>& prod_prob,
                    const std::vector<Point2>& points) {
  const int T = table.top_resolution(), N = table.fine_resolution();
  const std::vector<float> levels = importance_levels(table);
  const int up = std::max(1, (512 + N - 1) / N), S = N * up;
  Image importance(S, S), dots(S, S);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      const float t = levels[std::size_t(y / up) * N + (x / up)];
      importance.blend(x, y, inferno(t));
      const float g = 0.08f + 0.32f * t;
      dots.blend(x, y, {g, g, g});
    }
  draw_overlays(importance, T, nullptr, normal, false, 0);
  const float dot_r = std::max(1.5f, S / 350.0f);
  draw_overlays(dots, T, &pp, normal, true, 0.25f);
  for (const Point2& p : points) dots.disc(p.x * S, p.y * S, dot_r, {1.0f, 0.9f, 0.1f});
  Image top = cell_image(T, env_prob), weights = cell_image(T, prod_prob);
  draw_overlays(top, T, nullptr, normal, true, 1.0f);
  draw_overlays(weights, T, &pp, normal, true, 1.0f);
  write_png((out / "importance.png").string(), importance);
  write_png((out / "top_level.png").string(), top);
  write_png((out / "product_weights.png").string(), weights);
  write_png((out / "product_samples.png").string(), dots);
}

Json map_json(const EnvironmentMap& map, const TableSettings& s) {
  const MapLoadReport& rep = map.load_report();
  return {{"path", s.env},
          {"format", rep.format},
          {"width", map.width()},
          {"height", map.height()},
          {"layout", to_string(map.layout())},
          {"scale", map.scale()},
          {"rotate_degrees", s.rotate_degrees},
          {"orientation", map.layout() == MapLayout::LatLong ? to_string(map.orientation()) : "n/a"},
          {"filter", to_string(map.filter())},
          {"repaired", {{"nan", rep.nan_texels}, {"inf", rep.inf_texels}, {"negative", rep.negative_texels}}}};
}

Json table_json(const ImportanceTable& table, const TableSettings& s, int threads) {
  const std::size_t bytes = table.bytes_used(), single = table.single_level_bytes();
  return {{"top_resolution", table.top_resolution()},
          {"cell_resolution", table.cell_resolution()},
          {"fine_resolution", table.fine_resolution()},
          {"build_seconds", table.build_seconds()},
          {"threads", threads},
          {"bytes_used", bytes},
          {"single_level_bytes", single},
          {"memory_ratio", double(bytes) / double(single)},
          {"integral", table.integral()},
          {"peak_ratio", s.table_options.peak_ratio}};
}

Json shading_json(const ProductSampler& sampler, const TableSettings& s, double prepare_ns) {
  const BsdfProxy& proxy = s.proxy;
  const PreparedProxy& pp = sampler.prepared_proxy();
  return {{"normal", vec_json(s.normal)},
          {"wo", vec_json(s.wo)},
          {"proxy",
           {{"diffuse", proxy.diffuse},
            {"translucent", proxy.translucent},
            {"reflection", proxy.reflection},
            {"refraction", proxy.refraction},
            {"alpha_r", proxy.alpha_reflection},
            {"alpha_t", proxy.alpha_refraction},
            {"ior", proxy.ior}}},
          {"transform", to_string(s.sampler_options.proxy.transform)},
          {"min_alpha", s.sampler_options.proxy.min_alpha},
          {"max_alpha", s.sampler_options.proxy.max_alpha},
          {"env_mix", s.sampler_options.env_mix},
          {"prepared",
           {{"alpha_r", pp.alpha_r}, {"alpha_t", pp.alpha_t}, {"eta", pp.eta}, {"tir", pp.tir},
            {"reflection_axis", vec_json(pp.r)}, {"refraction_axis", vec_json(pp.t)}}},
          {"environment_fallback", sampler.uses_environment_fallback()},
          {"prepare_ns", prepare_ns},
          {"simd", to_string(sampler.simd())}};
}

Json samples_json(const SampleStats& st, const TableSettings& s) {
  return {{"count", s.samples},
          {"seed", s.seed},
          {"above_surface", double(st.above) / double(s.samples)},
          {"top_cells", st.top_k},
          {"top_cells_observed", st.observed_top},
          {"top_cells_expected", st.expected_top},
          {"max_pdf_relative_error", st.max_rel},
          {"zero_pdf", st.rejected}};
}

void write_json(const fs::path& path, const Json& j) {
  std::ofstream f(path);
  if (!f || !(f << j.dump(2) << '\n') || !f.flush()) throw Error("cannot write '" + path.string() + "'");
}

void run_table(const TableArgs& a) {
  // 1. Everything cheap is checked before touching the file system.
  const TableSettings s = parse_table_args(a);
  // 2. The map.
  const EnvironmentMap map = load_map(s);
  // 3. The table.
  const ImportanceTable table(map, s.table_options);
  const int threads = tbb::this_task_arena::max_concurrency();
  print_table_figures(table, threads);
  if (table.empty()) throw Error(no_radiance(s.env, "importance table is empty"));
  // 4. The product for the shading point.
  ProductSampler sampler(table, s.sampler_options);
  const double prepare_ns = prepare_product(sampler, s);
  const int T = table.top_resolution();
  std::vector<float> env_prob(std::size_t(T) * T), prod_prob(std::size_t(T) * T);
  for (int c = 0; c < T * T; ++c) {
    env_prob[c] = table.cell_probability(c);
    prod_prob[c] = sampler.cell_probability(c);
  }
  // 5. Samples.
  const SampleStats st = draw_samples(sampler, table, s, prod_prob);
  // 6. Pictures.
  write_pictures(s.out, table, sampler.prepared_proxy(), s.normal, env_prob, prod_prob, st.points);
  // 7. summary.json.
  Json j;
  j["version"] = kVersion;
  j["map"] = map_json(map, s);
  j["table"] = table_json(table, s, threads);
  j["shading_point"] = shading_json(sampler, s, prepare_ns);
  j["samples"] = samples_json(st, s);
  j["cells"] = {{"environment_probability", env_prob}, {"product_probability", prod_prob}, {"samples", st.per_cell}};
  j["outputs"] = {"map.png", "importance.png", "top_level.png", "product_weights.png", "product_samples.png"};
  write_json(s.out / "summary.json", j);
  std::printf("wrote:   %s/{map,importance,top_level,product_weights,product_samples}.png, summary.json\n",
              s.out.string().c_str());
}

const RegisterCommand kTable{Command{
    "table", "Build an environment map's importance table, print its figures and write pictures of it",
    [](CLI::App& sub) {
      auto a = std::make_shared<TableArgs>();
      add_table_options(sub, *a);
      sub.callback([a] { run_table(*a); });
    }}};

}  // namespace
}  // namespace envpis::app
