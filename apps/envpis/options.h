// SPDX-License-Identifier: Apache-2.0
// Option parsing shared by the envpis subcommands: strict numbers whose errors are one line naming the
// option ("--spp: must be in 1..16777216, got '0'"), and the scene / environment / sampling options that
// `envpis render` and `envpis compare` both take.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "envpis/envpis.h"

#ifdef ENVPIS_HAVE_RENDER
#include "render/render.h"
#include "render/scene.h"
#endif

namespace envpis::app {

/// A finite number; throws Error "OPTION: expected a finite number, got 'TEXT'".
double parse_number(const std::string& option, const std::string& text);
/// A finite number in [lo, hi]; `range` describes the interval in the message ("in [0, 1]", ">= 0").
double parse_number_in(const std::string& option, const std::string& text, double lo, double hi, const char* range);
/// --peak-ratio: 0 (the bound off) or a number in [1, 1e6].
float parse_peak_ratio(const std::string& text);
/// A decimal integer in lo..hi.
long long parse_integer(const std::string& option, const std::string& text, long long lo, long long hi);
std::string lower(std::string s);

/// Runs a library parser and prefixes its error with the option's name ("--env-filter: unknown ...").
template <class F>
auto with_option(const std::string& option, F&& parse) {
  try {
    return parse();
  } catch (const Error& e) {
    throw Error(option + ": " + e.what());
  }
}
/// Fails early (before anything slow) when the file `path` cannot be created or written; leaves no
/// file behind that was not there.
void check_writable_file(const std::string& path, const std::string& option);

#ifdef ENVPIS_HAVE_RENDER
/// The options `render` and `compare` share, kept as text until parse time so every error is reported
/// the same way. Defaults are the renderer's, except the integrator (each command has its own).
struct SceneOptionArgs {
  std::string scene = "fig1";
  std::string env, env_rotation = "0", env_scale = "1";
  std::string env_orientation, env_filter;  // empty: the library's defaults (panorama, bilinear)
  std::string integrator;
  std::string heuristic = "power";
  std::string sampler = "sobol";
  std::string max_depth = "8";
  std::string threads = "0";
  std::string top = "12", fine = "0", subcells = "4";
  std::string peak_ratio;  // empty: the library's default
  std::string fine_texels = "auto";  // the renderer's default: the map's own texels for lat-long maps
  std::string oracle_res = "48", oracle_dirs = "4", oracle_compensation = "on";
  std::string proxy_transform, proxy_lobe, proxy_min_alpha, proxy_max_alpha, env_mix, env_floor, refine_cells,
      cell_estimate;  // empty: the library's defaults
  std::string closed_surfaces;  // empty: the scene's setting (on for built-in scenes)
  std::string product_cache = "64", product_cache_resolution = "64", product_depth = "0";
  std::string product_cache_step = "0.03125";
  std::string product_max_roughness = "0.5";  // docs/assets.md, "by the vertex's material"
  std::string product_compensation = "auto";  // docs/assets.md, "`auto`: the compensated product along paths"
  // Path regularization (render/regularization.h): Cycles' clamp, caustics and filter glossy; off.
  std::string clamp_direct = "0", clamp_indirect = "0", caustics = "reflective,refractive", filter_glossy = "0";

  explicit SceneOptionArgs(std::string default_integrator) : integrator(std::move(default_integrator)) {}

  /// --scene, --env, --env-rotation, --env-scale, --env-orientation, --env-filter.
  void add_scene_options(CLI::App& sub);
  /// --integrator, --heuristic, --sampler, --max-depth, --threads, --top, --oracle-*, --proxy-*, --env-mix,
  /// --closed-surfaces, and the path regularization (--clamp-direct, --clamp-indirect, --caustics,
  /// --filter-glossy).
  void add_sampling_options(CLI::App& sub);
  /// Parses the sampling options into `o` (throws Error naming the option).
  void apply(render::RenderOptions& o) const;
  /// --clamp-direct, --clamp-indirect, --caustics, --filter-glossy (part of add_sampling_options).
  void add_regularization_options(CLI::App& sub);
  void apply_regularization(render::RegularizationOptions& r) const;
  /// Checks --env-rotation / --env-scale / --env-orientation / --env-filter (throws Error naming the
  /// option; each needs --env).
  EnvironmentMapOptions map_options() const;
  /// --closed-surfaces: -1 for the scene's setting (not given), else 0 (off) or 1 (on); throws Error
  /// for any other value.
  int closed_surfaces_override() const;
  /// Loads --env (if given; its warnings go to stderr as "envpis COMMAND: warning: ...") and the scene
  /// (built-in or JSON file), with --closed-surfaces applied. `env` receives the loaded map, null
  /// without --env.
  render::Scene load_scene(const std::string& command, std::shared_ptr<const EnvironmentMap>* env) const;
};
#endif

}  // namespace envpis::app
