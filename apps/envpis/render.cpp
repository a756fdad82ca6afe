// SPDX-License-Identifier: Apache-2.0
// envpis render: renders a built-in or file scene with one sampling strategy to a float OpenEXR.
#ifdef ENVPIS_HAVE_RENDER

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "command.h"
#include "options.h"
#include "envpis/envpis.h"
#include "render/render.h"
#include "render/scenes.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using namespace envpis::render;

struct RenderArgs {
  SceneOptionArgs common{"path"};
  std::string strategy = "product";
  std::string spp = "64";
  std::string seed = "0";
  std::string width = "0", height = "0";
  std::string out;
  std::string id_out;
  std::string firefly_log, firefly_threshold;  // empty: no log
  bool quiet = false;
};

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled) {}
  void update(double fraction) {
    if (!enabled_) return;
    constexpr int kWidth = 40;
    const int filled = static_cast<int>(fraction * kWidth + 0.5);
    std::fprintf(stderr, "\r[%-*s] %3d%%", kWidth, std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 static_cast<int>(fraction * 100 + 0.5));
    std::fflush(stderr);
  }
  void finish() {
    if (enabled_) std::fprintf(stderr, "\r%*s\r", 48, "");
  }

 private:
  bool enabled_;
};

void run(const RenderArgs& a) {
  // 1. Options (all validated before anything slow happens).
  RenderOptions o;
  o.strategy = parse_strategy(a.strategy);
  a.common.apply(o);
  o.spp = static_cast<int>(parse_integer("--spp", a.spp, 1, kMaxSpp));
  o.seed = static_cast<std::uint64_t>(parse_integer("--seed", a.seed, 0, INT64_MAX));
  o.width = static_cast<int>(parse_integer("--width", a.width, 0, kMaxImageSide));
  o.height = static_cast<int>(parse_integer("--height", a.height, 0, kMaxImageSide));
  a.common.map_options();
  validate(o);
  if (a.out.empty()) throw Error("--out is required");
  const std::string ext = lower(fs::path(a.out).extension().string());
  if (ext != ".exr") throw Error("--out must name an OpenEXR file (.exr), got '" + a.out + "'");
  check_writable_file(a.out, "--out");
  if (!a.id_out.empty()) check_writable_file(a.id_out, "--id-out");
  FireflyLogOptions log;
  if (!a.firefly_log.empty() || !a.firefly_threshold.empty()) {
    if (a.firefly_threshold.empty()) throw Error("--firefly-log needs --firefly-threshold");
    if (a.firefly_log.empty()) throw Error("--firefly-threshold needs --firefly-log");
    log.threshold = static_cast<float>(parse_number_in("--firefly-threshold", a.firefly_threshold, 0, 3.0e38, "> 0"));
    if (!(log.threshold > 0)) throw Error("--firefly-threshold: must be > 0, got '" + a.firefly_threshold + "'");
    check_writable_file(a.firefly_log, "--firefly-log");
    o.firefly_log = &log;
  }

  // 2. Scene and environment.
  std::shared_ptr<const EnvironmentMap> env;
  Scene scene = a.common.load_scene("render", &env);
  if (scene.has_environment() && scene.environment().is_black())
    std::fprintf(stderr,
                 "envpis render: warning: the environment (%s) has no positive radiance: it lights nothing, "
                 "every strategy falls back to BSDF sampling, the image is black\n",
                 scene.environment_description().c_str());

  // 3. Render.
  ProgressBar bar(!a.quiet && isatty(STDERR_FILENO));
  o.progress = [&bar](double f) { bar.update(f); };
  const RenderResult r = envpis::render::render(scene, o);
  bar.finish();
  write_exr(a.out, r);
  if (!a.id_out.empty()) write_object_id(a.id_out, r);
  if (o.firefly_log) write_firefly_csv(a.firefly_log, r.fireflies);

  // 4. Summary.
  std::printf("scene        %s (%zu objects), environment %s\n", a.common.scene.c_str(), scene.objects().size(),
              scene.environment_description().c_str());
  std::printf("resolution   %dx%d\n", r.width, r.height);
  std::printf("spp          %d (seed %llu)\n", r.spp, static_cast<unsigned long long>(o.seed));
  std::printf("strategy     %s, integrator %s", to_string(o.strategy), to_string(o.integrator));
  if (o.integrator == IntegratorKind::Path) std::printf(" (max depth %d)", o.max_depth);
  std::printf(", heuristic %s, sampler %s\n", to_string(o.heuristic), to_string(o.sampler));
  std::printf("wall seconds %.3f (tables %.3f s; CPU %.3f s)\n", r.seconds, r.setup_seconds, r.cpu_seconds);
  std::printf("samples/s    %.4g\n", r.seconds > 0 ? double(r.samples) / r.seconds : 0.0);
  if (const std::uint64_t n = r.product_cache_hits + r.product_cache_misses; n > 0)
    std::printf("product      %.1f%% of %llu shading points reused a prepared distribution\n",
                100.0 * double(r.product_cache_hits) / double(n), static_cast<unsigned long long>(n));
  if (r.nonfinite_pixels > 0) std::printf("non-finite   %zu pixels set to 0\n", r.nonfinite_pixels);
  if (o.firefly_log) {
    std::printf("fireflies    %zu samples above %g in %s", r.fireflies.size(), double(log.threshold),
                a.firefly_log.c_str());
    if (r.fireflies_dropped > 0) std::printf(" (%zu more not kept: raise the threshold)", r.fireflies_dropped);
    std::printf("\n");
  }
  std::printf("wrote        %s\n", a.out.c_str());
}

const RegisterCommand reg{{"render", "Render a scene with one sampling strategy to a float OpenEXR",
                           [](CLI::App& sub) {
                             auto a = std::make_shared<RenderArgs>();
                             a->common.add_scene_options(sub);
                             sub.add_option("--strategy", a->strategy, "bsdf, env, mis, mis-comp, product or oracle")->type_name("S")
                                 ->capture_default_str();
                             sub.add_option("--spp", a->spp, "samples per pixel")->type_name("INT")->capture_default_str();
                             sub.add_option("--seed", a->seed, "random seed")->type_name("INT")->capture_default_str();
                             sub.add_option("--width", a->width, "image width (0: the scene's)")->type_name("INT")->capture_default_str();
                             sub.add_option("--height", a->height, "image height (0: the scene's)")->type_name("INT")->capture_default_str();
                             a->common.add_sampling_options(sub);
                             sub.add_option("--out", a->out, "output OpenEXR file")->type_name("FILE.exr");
                             sub.add_option("--id-out", a->id_out, "also write the object-id AOV (first hit per pixel)")->type_name("FILE");
                             sub.add_option("--firefly-log", a->firefly_log,
                                            "write every sample contribution above --firefly-threshold as CSV "
                                            "(docs/fireflies.md)")->type_name("FILE.csv");
                             sub.add_option("--firefly-threshold", a->firefly_threshold,
                                            "firefly log: channel-average radiance one sample adds to its pixel "
                                            "sum at one vertex (> 0)")->type_name("T");
                             sub.add_flag("--quiet", a->quiet, "no progress bar");
                             sub.callback([a] { run(*a); });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
