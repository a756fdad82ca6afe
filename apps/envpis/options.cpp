// SPDX-License-Identifier: Apache-2.0
#include "options.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <unistd.h>

#ifdef ENVPIS_HAVE_RENDER
#include "render/scenes.h"
#endif

namespace envpis::app {

namespace fs = std::filesystem;

double parse_number(const std::string& option, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s, &end);
  if (text.empty() || end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v))
    throw Error(option + ": expected a finite number, got '" + text + "'");
  return v;
}

double parse_number_in(const std::string& option, const std::string& text, double lo, double hi, const char* range) {
  const double v = parse_number(option, text);
  if (!(v >= lo && v <= hi)) throw Error(option + ": must be " + range + ", got '" + text + "'");
  return v;
}

float parse_peak_ratio(const std::string& text) {
  const float k = static_cast<float>(parse_number_in("--peak-ratio", text, 0, 1e6, "0 (off) or in [1, 1e6]"));
  if (k > 0 && k < 1) throw Error("--peak-ratio: must be 0 (off) or in [1, 1e6], got '" + text + "'");
  return k;
}

long long parse_integer(const std::string& option, const std::string& text, long long lo, long long hi) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s, &end, 10);
  const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
  if (text.empty() || end == s || *end != '\0' || errno == ERANGE)
    throw Error(option + ": expected an integer in " + range + ", got '" + text + "'");
  if (v < lo || v > hi) throw Error(option + ": must be in " + range + ", got '" + text + "'");
  return v;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

void check_writable_file(const std::string& path, const std::string& option) {
  const fs::path p(path);
  if (p.filename().empty()) throw Error(option + ": '" + path + "' is not a file name");
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw Error(option + ": '" + path + "' is a directory");
  // Create exclusively, so only a file this call made is removed: with "exists? create, remove" two
  // commands writing the same path at once could leave an empty file behind (seen in CI).
  for (int attempt = 0; attempt < 4; ++attempt) {
    int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      ::unlink(path.c_str());
      return;
    }
    if (errno != EEXIST) break;
    fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);  // there already: writable, left untouched
    if (fd >= 0) {
      ::close(fd);
      return;
    }
    if (errno != ENOENT) break;  // ENOENT: removed meanwhile by another writer, try again
  }
  throw Error("cannot write " + option + " '" + path + "': " + std::strerror(errno));
}

#ifdef ENVPIS_HAVE_RENDER

using namespace envpis::render;

void SceneOptionArgs::add_scene_options(CLI::App& sub) {
  sub.add_option("--scene", scene, "fig1, fig5 or a JSON scene file (docs/scene-format.md)")
      ->type_name("NAME|FILE")
      ->capture_default_str();
  sub.add_option("--env", env, "environment map (EXR/HDR); default: the scene's (docs/scene-format.md)")
      ->type_name("FILE");
  sub.add_option("--env-rotation", env_rotation, "rotation of --env about +Z, degrees")->type_name("DEG");
  sub.add_option("--env-scale", env_scale, "radiance scale of --env (>= 0)")->type_name("FLOAT");
  sub.add_option("--env-orientation", env_orientation,
                 "lat-long --env: panorama (Blender/Cycles: +X at the centre column; default) or legacy (+X at "
                 "the left edge, mirrored)")
      ->type_name("O");
  sub.add_option("--env-filter", env_filter, "radiance look-up in --env: bilinear (default) or nearest")
      ->type_name("F");
}

void SceneOptionArgs::add_sampling_options(CLI::App& sub) {
  sub.add_option("--integrator", integrator, "direct or path")->type_name("I")->capture_default_str();
  sub.add_option("--heuristic", heuristic, "MIS heuristic: power or balance")->type_name("H")->capture_default_str();
  sub.add_option("--sampler", sampler,
                 "random numbers: sobol (one Owen-scrambled Sobol point per sample: pixel position and samples "
                 "stratified jointly), padded (every pair past the pixel its own (0,2)-sequence) or independent")
      ->type_name("S")
      ->capture_default_str();
  sub.add_option("--max-depth", max_depth, "path integrator: maximum bounces")->type_name("INT")->capture_default_str();
  sub.add_option("--threads", threads, "worker threads (0: all)")->type_name("INT")->capture_default_str();
  sub.add_option("--top", top, "light table: top-level cells per side (env, mis, mis-comp, product), 1..256")
      ->type_name("INT")
      ->capture_default_str();
  sub.add_option("--fine", fine,
                 "light tables: fine texels per side, rounded up to a multiple of --top (0: the smallest with at "
                 "least the map's texel count)")
      ->type_name("N")
      ->capture_default_str();
  sub.add_option("--fine-texels", fine_texels,
                 "light tables: the fine level's texels: equal-area (N x N, see --fine), map (a lat-long map's own "
                 "texels: a light sample's weight is constant over each map texel; docs/cycles.md) or auto (map "
                 "for lat-long maps read with --env-filter nearest, else equal-area); the oracle always uses "
                 "equal-area")
      ->type_name("equal-area|map|auto")
      ->capture_default_str();
  sub.add_option("--peak-ratio", peak_ratio,
                 "light tables: each texel's importance is at least 1/K of the radiance eval reaches in it "
                 "(K; 0: off; default: the library's)")
      ->type_name("K");
  sub.add_option("--oracle-res", oracle_res, "oracle: top cells per side, 1..256")->type_name("INT")->capture_default_str();
  sub.add_option("--oracle-dirs", oracle_dirs, "oracle: first-pass points per top cell (a square number; docs/analyzer.md)")
      ->type_name("INT")
      ->capture_default_str();
  sub.add_option("--oracle-compensation", oracle_compensation,
                 "oracle: weight its cells for MIS with the BSDF sample (on) or by their share alone (off)")
      ->type_name("on|off")
      ->capture_default_str();
  sub.add_option("--proxy-transform", proxy_transform, "product: proxy roughness transform (default: the library's)")
      ->type_name("T");
  sub.add_option("--proxy-lobe", proxy_lobe,
                 "product: the proxy's reflection lobe, mirror (the paper's, around the mirror direction, with "
                 "--proxy-transform; the library's default) or half-vector (GGX of the half-vector at the BSDF's "
                 "roughness; docs/proxy.md) (default: half-vector)")
      ->type_name("mirror|half-vector");
  sub.add_option("--proxy-min-alpha", proxy_min_alpha,
                 "product: floor on the transformed proxy roughness, [0, 1] (default: 0.2 with --cell-estimate "
                 "moments, else the library's, 0.35)")
      ->type_name("FLOAT");
  sub.add_option("--closed-surfaces", closed_surfaces,
                 "product and oracle: leave out light samples into closed transmissive objects (default: the "
                 "scene's, on unless a scene file says \"closed_surfaces\": false)")
      ->type_name("on|off");
  sub.add_option("--proxy-max-alpha", proxy_max_alpha,
                 "product: cap on the transformed proxy roughness, [0, 1] (default: the library's)")
      ->type_name("FLOAT");
  sub.add_option("--subcells", subcells,
                 "product: S, the sub-cells per top cell along each axis that the product weights again inside "
                 "the chosen cell (the light tables get S x S sub-cells), 1..8; 1: the paper's one-level product "
                 "(docs/refinement.md)")
      ->type_name("S")
      ->capture_default_str();
  sub.add_option("--refine-cells", refine_cells,
                 "product with --subcells > 1: the heaviest top cells (up to this many, 0..64) re-weighed from "
                 "their sub-cells in prepare (default: the library's, 0)")
      ->type_name("K");
  sub.add_option("--cell-estimate", cell_estimate,
                 "product: how a cell's proxy value is estimated: cone (the paper's, the lobes at the cell's "
                 "bounding cone) or moments (at its importance-weighted mean direction; "
                 "docs/refinement.md) (default: moments; the library's is cone)")
      ->type_name("cone|moments");
  sub.add_option("--product-cache", product_cache,
                 "product: prepared distributions kept per thread and shared by shading points that round to the "
                 "same normal, view and material (envpis/product_cache.h), 0..1024; 0: prepare every shading "
                 "point exactly")
      ->type_name("N")
      ->capture_default_str();
  sub.add_option("--product-depth", product_depth,
                 "product: the product distribution at the first D vertices of a path, the environment "
                 "table's (as mis) deeper; 0: at every vertex. 0..1024")
      ->type_name("D")
      ->capture_default_str();
  sub.add_option("--product-compensation", product_compensation,
                 "product: which distributions use the MIS-compensated table (max(0, importance - mean), as "
                 "mis-comp's): off (none), elsewhere (the vertices without the product sample mis-comp's "
                 "table instead of mis's), deeper (those and the product's environment factor below a camera "
                 "ray's hit), on (at every vertex), on-without-portals (on for product, off for product-portal) or "
                 "auto: on-without-portals with the path integrator, deeper with the direct one")
      ->type_name("off|elsewhere|deeper|on|on-without-portals|auto")
      ->capture_default_str();
  sub.add_option("--product-max-roughness", product_max_roughness,
                 "product: the product distribution only at vertices with a reflection or refraction lobe "
                 "of GGX alpha <= A, the environment table's (as mis) at the others (diffuse-only, rough); with the "
                 "product cache, a camera ray's hit always gets the product; inf: at every vertex "
                 "(RenderOptions' default). [0, 1] or inf")
      ->type_name("A")
      ->capture_default_str();
  sub.add_option("--product-cache-resolution", product_cache_resolution,
                 "product with --product-cache: K, the normal's and the view's components are rounded to "
                 "multiples of 1/K (a direction moves by at most 0.87 / K radians), 1..4095")
      ->type_name("B")
      ->capture_default_str();
  sub.add_option("--product-cache-step", product_cache_step,
                 "product-portal with --product-cache: the shading point is rounded to multiples of F times the "
                 "smallest portal's longer diagonal (a portal then moves by less than F of its own angular size), "
                 "(0, 1]")
      ->type_name("F")
      ->capture_default_str();
  sub.add_option("--env-floor", env_floor,
                 "product: every cell the proxy sees keeps at least this times its environment share, [0, 1] "
                 "(default: the library's)")
      ->type_name("R");
  sub.add_option("--env-mix", env_mix,
                 "product: fraction of environment-only sampling mixed in, [0, 1] (default: the library's)")
      ->type_name("FLOAT");
  add_regularization_options(sub);
}

void SceneOptionArgs::add_regularization_options(CLI::App& sub) {
  sub.add_option("--clamp-direct", clamp_direct,
                 "path regularization (Cycles' Clamp Direct): each contribution after at most one surface "
                 "interaction is scaled so its channel mean is at most X; 0: off")
      ->type_name("X")
      ->capture_default_str();
  sub.add_option("--clamp-indirect", clamp_indirect,
                 "path regularization (Cycles' Clamp Indirect): the same for every other contribution; 0: off")
      ->type_name("X")
      ->capture_default_str();
  sub.add_option("--caustics", caustics,
                 "path regularization (Cycles' Reflective / Refractive Caustics): the glossy parts a vertex "
                 "keeps after a diffuse bounce: reflective,refractive (all: no regularization), reflective, "
                 "refractive or none")
      ->type_name("LIST")
      ->capture_default_str();
  sub.add_option("--filter-glossy", filter_glossy,
                 "path regularization (Cycles' Filter Glossy): after BSDF samples of smallest pdf p < X, GGX "
                 "alpha is raised to at least 0.5 sqrt(1 - p / X); 0: off")
      ->type_name("X")
      ->capture_default_str();
}

void SceneOptionArgs::apply_regularization(RegularizationOptions& r) const {
  const char* range = ">= 0 (0: off)";
  r.clamp_direct = static_cast<float>(parse_number_in("--clamp-direct", clamp_direct, 0, 3.0e38, range));
  r.clamp_indirect = static_cast<float>(parse_number_in("--clamp-indirect", clamp_indirect, 0, 3.0e38, range));
  r.filter_glossy = static_cast<float>(parse_number_in("--filter-glossy", filter_glossy, 0, 3.0e38, range));
  with_option("--caustics", [&] {
    parse_caustics(caustics, &r);
    return 0;
  });
}

void SceneOptionArgs::apply(RenderOptions& o) const {
  closed_surfaces_override();
  o.integrator = parse_integrator(integrator);
  o.heuristic = parse_heuristic(heuristic);
  try {
    o.sampler = parse_sampler(sampler);
  } catch (const Error& e) {
    throw Error(std::string("--sampler: ") + e.what());
  }
  o.max_depth = static_cast<int>(parse_integer("--max-depth", max_depth, 1, 1024));
  apply_regularization(o.regularization);
  o.threads = static_cast<int>(parse_integer("--threads", threads, 0, 4096));
  o.light_table.top_resolution = static_cast<int>(parse_integer("--top", top, 1, 256));
  o.light_table.fine_resolution = static_cast<int>(parse_integer("--fine", fine, 0, 16384));
  if (!peak_ratio.empty()) o.light_table.peak_ratio = parse_peak_ratio(peak_ratio);
  try {
    o.light_table.fine_texels = parse_fine_texels(fine_texels);
  } catch (const Error& e) {
    throw Error(std::string("--fine-texels: ") + e.what());
  }
  o.oracle.resolution = static_cast<int>(parse_integer("--oracle-res", oracle_res, 1, 256));
  o.oracle.directions = static_cast<int>(parse_integer("--oracle-dirs", oracle_dirs, 1, 256));
  const int k = static_cast<int>(std::lround(std::sqrt(double(o.oracle.directions))));
  if (k * k != o.oracle.directions)
    throw Error("--oracle-dirs: must be a square number (1, 4, 9, 16, ...), got '" + oracle_dirs + "'");
  if (oracle_compensation != "on" && oracle_compensation != "off")
    throw Error("--oracle-compensation: expected on or off, got '" + oracle_compensation + "'");
  o.oracle.mis_compensation = oracle_compensation == "on";
  if (!proxy_transform.empty()) {
    try {
      o.product.proxy.transform = parse_roughness_transform(proxy_transform);
    } catch (const Error& e) {
      throw Error(std::string("--proxy-transform: ") + e.what());
    }
  }
  // The half-vector lobe by default: measured on fig1, the Cycles sphere and the asset scenes
  // (docs/proxy.md, "The half-vector lobe"); the library keeps the paper's mirror lobe.
  try {
    o.product.proxy.reflection_lobe = parse_reflection_lobe(proxy_lobe.empty() ? "half-vector" : proxy_lobe);
  } catch (const Error& e) {
    throw Error(std::string("--proxy-lobe: ") + e.what());
  }
  if (!proxy_min_alpha.empty())
    o.product.proxy.min_alpha = static_cast<float>(parse_number_in("--proxy-min-alpha", proxy_min_alpha, 0, 1, "in [0, 1]"));
  if (!proxy_max_alpha.empty())
    o.product.proxy.max_alpha = static_cast<float>(parse_number_in("--proxy-max-alpha", proxy_max_alpha, 0, 1, "in [0, 1]"));
  if (!env_mix.empty()) o.product.env_mix = static_cast<float>(parse_number_in("--env-mix", env_mix, 0, 1, "in [0, 1]"));
  o.light_table.subdivision = static_cast<int>(parse_integer("--subcells", subcells, 1, 8));
  o.product.refine = o.light_table.subdivision > 1;
  if (!refine_cells.empty())
    o.product.refine_cells = static_cast<int>(parse_integer("--refine-cells", refine_cells, 0, 64));
  // The renderer's default is moments (docs/refinement.md, measured with the analyzer), as its default
  // --subcells is 4; the library's defaults stay the paper's sampler.
  try {
    o.product.cell_estimate = parse_cell_estimate(cell_estimate.empty() ? "moments" : cell_estimate);
  } catch (const Error& e) {
    throw Error(std::string("--cell-estimate: ") + e.what());
  }
  // The roughness floor was the cone's remedy (a narrow lobe gives its peak to every cell its cone
  // reaches); with moments a lower one pays under MIS (docs/refinement.md), unless --proxy-min-alpha.
  if (proxy_min_alpha.empty() && o.product.cell_estimate == CellEstimate::Moments) o.product.proxy.min_alpha = 0.2f;
  o.product_cache.entries = static_cast<int>(parse_integer("--product-cache", product_cache, 0, 1024));
  o.product_depth = static_cast<int>(parse_integer("--product-depth", product_depth, 0, 1024));
  if (product_max_roughness != "inf")
    o.product_max_roughness = static_cast<float>(
        parse_number_in("--product-max-roughness", product_max_roughness, 0, 1, "in [0, 1] or inf"));
  // auto: measured per integrator (docs/assets.md, "`auto`: the compensated product along paths").
  o.product_compensation = with_option("--product-compensation", [&] {
    if (product_compensation == "auto")
      return o.integrator == render::IntegratorKind::Path ? render::ProductCompensation::OnWithoutPortals
                                                          : render::ProductCompensation::Deeper;
    try {
      return parse_product_compensation(product_compensation);
    } catch (const Error&) {
      throw Error("unknown product compensation '" + product_compensation + "' (expected " +
                  render::product_compensation_names("auto") + ")");
    }
  });
  o.product_cache.resolution =
      static_cast<int>(parse_integer("--product-cache-resolution", product_cache_resolution, 1, 4095));
  o.product_cache_step = static_cast<float>(
      parse_number_in("--product-cache-step", product_cache_step, 0, 1, "in (0, 1]"));
  if (!(o.product_cache_step > 0)) throw Error("--product-cache-step: must be in (0, 1], got " + product_cache_step);
  if (!env_floor.empty())
    o.product.env_floor = static_cast<float>(parse_number_in("--env-floor", env_floor, 0, 1, "in [0, 1]"));
  // ENVPIS_SIMD (best, scalar, sse2, avx2, avx512) picks the product sampler's kernels, for
  // benchmarking and debugging; the library itself never reads the environment.
  if (const char* simd = std::getenv("ENVPIS_SIMD")) {
    try {
      o.product.simd = simd_resolve(parse_simd(simd));
    } catch (const Error& e) {
      throw Error(std::string("ENVPIS_SIMD: ") + e.what());
    }
  }
}

int SceneOptionArgs::closed_surfaces_override() const {
  if (closed_surfaces.empty()) return -1;
  if (closed_surfaces == "on") return 1;
  if (closed_surfaces == "off") return 0;
  throw Error("--closed-surfaces: expected on or off, got '" + closed_surfaces + "'");
}

EnvironmentMapOptions SceneOptionArgs::map_options() const {
  EnvironmentMapOptions mo;
  mo.rotation = Mat3::rotate_z(
      static_cast<float>(parse_number_in("--env-rotation", env_rotation, -1e6, 1e6, "in [-1e6, 1e6] degrees")));
  mo.scale = static_cast<float>(parse_number_in("--env-scale", env_scale, 0, 3.0e38, ">= 0"));
  if (!env_orientation.empty())
    mo.orientation = with_option("--env-orientation", [&] { return parse_latlong_orientation(env_orientation); });
  if (!env_filter.empty()) mo.filter = with_option("--env-filter", [&] { return parse_map_filter(env_filter); });
  if (env.empty()) {  // they describe --env; a scene file's environment has its own fields
    if (env_rotation != "0") throw Error("--env-rotation needs --env");
    if (env_scale != "1") throw Error("--env-scale needs --env");
    if (!env_orientation.empty()) throw Error("--env-orientation needs --env");
    if (!env_filter.empty()) throw Error("--env-filter needs --env");
  }
  return mo;
}

Scene SceneOptionArgs::load_scene(const std::string& command, std::shared_ptr<const EnvironmentMap>* env_out) const {
  std::shared_ptr<const EnvironmentMap> map;
  const EnvironmentMapOptions mo = map_options();
  if (!env.empty()) {
    map = std::make_shared<const EnvironmentMap>(EnvironmentMap::load(env, mo));
    for (const std::string& w : map->warnings())
      std::fprintf(stderr, "envpis %s: warning: %s\n", command.c_str(), w.c_str());
  }
  if (env_out) *env_out = map;
  const int closed = closed_surfaces_override();
  Scene sc = [&] {
    if (is_builtin_scene(scene)) return make_builtin_scene(scene, map);
    std::error_code ec;
    if (!fs::is_regular_file(scene, ec)) {
      if (scene.find('/') != std::string::npos || scene.find('.') != std::string::npos)
        throw Error("scene file '" + scene + "' does not exist");
      throw Error("unknown scene '" + scene + "' (built-in scenes: fig1, fig5; or a .json scene file)");
    }
    return load_scene_file(scene, map);
  }();
  if (closed >= 0) sc.set_proxy_closed_surfaces(closed == 1);
  return sc;
}

#endif  // ENVPIS_HAVE_RENDER

}  // namespace envpis::app
