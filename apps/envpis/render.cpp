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
#include "envpis/envpis.h"
#include "render/render.h"
#include "render/scenes.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using namespace envpis::render;

struct RenderArgs {
  std::string scene = "fig1";
  std::string env;
  std::string env_rotation = "0";
  std::string env_scale = "1";
  std::string strategy = "product";
  std::string spp = "64";
  std::string seed = "0";
  std::string width = "0", height = "0";
  std::string threads = "0";
  std::string integrator = "path";
  std::string heuristic = "power";
  std::string max_depth = "8";
  std::string oracle_res = "64";
  std::string oracle_dirs = "4";
  std::string proxy_transform;  // empty: the library's defaults (ProductSamplerOptions)
  std::string proxy_min_alpha;
  std::string env_mix;
  std::string out;
  std::string id_out;
  bool quiet = false;
};

long long parse_int(const std::string& name, const std::string& s, long long lo, long long hi) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno == ERANGE)
    throw Error(name + " must be an integer, got '" + s + "'");
  if (v < lo || v > hi)
    throw Error(name + " must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + s);
  return v;
}

float parse_float(const std::string& name, const std::string& s) {
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v)) throw Error(name + " must be a finite number, got '" + s + "'");
  return v;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

/// Fails early (before rendering) when `path` cannot be written.
void check_writable(const std::string& path, const char* what) {
  const fs::path p(path);
  if (p.filename().empty()) throw Error(std::string(what) + " '" + path + "' is not a file name");
  std::error_code ec;
  const bool existed = fs::exists(p, ec);
  if (existed && fs::is_directory(p, ec)) throw Error(std::string(what) + " '" + path + "' is a directory");
  std::FILE* f = std::fopen(path.c_str(), "ab");
  if (!f) throw Error(std::string("cannot write ") + what + " '" + path + "': " + std::strerror(errno));
  std::fclose(f);
  if (!existed) fs::remove(p, ec);
}

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
  o.integrator = parse_integrator(a.integrator);
  o.heuristic = parse_heuristic(a.heuristic);
  o.spp = static_cast<int>(parse_int("--spp", a.spp, 1, kMaxSpp));
  o.seed = static_cast<std::uint64_t>(parse_int("--seed", a.seed, 0, INT64_MAX));
  o.width = static_cast<int>(parse_int("--width", a.width, 0, kMaxImageSide));
  o.height = static_cast<int>(parse_int("--height", a.height, 0, kMaxImageSide));
  o.threads = static_cast<int>(parse_int("--threads", a.threads, 0, 4096));
  o.max_depth = static_cast<int>(parse_int("--max-depth", a.max_depth, 1, 1024));
  o.oracle.resolution = static_cast<int>(parse_int("--oracle-res", a.oracle_res, 1, 256));
  o.oracle.directions = static_cast<int>(parse_int("--oracle-dirs", a.oracle_dirs, 1, 256));
  if (!a.proxy_transform.empty()) o.product.proxy.transform = parse_roughness_transform(a.proxy_transform);
  if (!a.proxy_min_alpha.empty()) {
    o.product.proxy.min_alpha = parse_float("--proxy-min-alpha", a.proxy_min_alpha);
    if (!(o.product.proxy.min_alpha >= 0 && o.product.proxy.min_alpha <= 1))
      throw Error("--proxy-min-alpha must be in [0, 1]");
  }
  if (!a.env_mix.empty()) {
    o.product.env_mix = parse_float("--env-mix", a.env_mix);
    if (!(o.product.env_mix >= 0 && o.product.env_mix <= 1)) throw Error("--env-mix must be in [0, 1]");
  }
  const float rotation = parse_float("--env-rotation", a.env_rotation);
  const float scale = parse_float("--env-scale", a.env_scale);
  if (scale < 0) throw Error("--env-scale must be >= 0");
  validate(o);
  if (a.out.empty()) throw Error("--out is required");
  const std::string ext = lower(fs::path(a.out).extension().string());
  if (ext != ".exr") throw Error("--out must name an OpenEXR file (.exr), got '" + a.out + "'");
  check_writable(a.out, "--out");
  if (!a.id_out.empty()) check_writable(a.id_out, "--id-out");

  // 2. Scene and environment.
  std::shared_ptr<const EnvironmentMap> env;
  if (!a.env.empty()) {
    EnvironmentMapOptions mo;
    mo.rotation = Mat3::rotate_z(rotation);
    mo.scale = scale;
    env = std::make_shared<const EnvironmentMap>(EnvironmentMap::load(a.env, mo));
    for (const std::string& w : env->warnings()) std::fprintf(stderr, "envpis render: warning: %s\n", w.c_str());
    if (env->is_black())
      std::fprintf(stderr,
                   "envpis render: warning: '%s' has no positive radiance: the environment lights nothing and "
                   "every strategy falls back to BSDF sampling (the image is black)\n",
                   a.env.c_str());
  } else if (a.env_rotation != "0" || a.env_scale != "1") {
    throw Error("--env-rotation and --env-scale need --env");
  }
  Scene scene = is_builtin_scene(a.scene) ? make_builtin_scene(a.scene, env) : [&] {
    std::error_code ec;
    if (!fs::is_regular_file(a.scene, ec)) {
      if (a.scene.find('/') != std::string::npos || a.scene.find('.') != std::string::npos)
        throw Error("scene file '" + a.scene + "' does not exist");
      throw Error("unknown scene '" + a.scene + "' (built-in scenes: fig1, fig5; or a .json scene file)");
    }
    return load_scene_file(a.scene, env);
  }();

  // 3. Render.
  ProgressBar bar(!a.quiet && isatty(STDERR_FILENO));
  o.progress = [&bar](double f) { bar.update(f); };
  const RenderResult r = envpis::render::render(scene, o);
  bar.finish();
  write_exr(a.out, r);
  if (!a.id_out.empty()) write_object_id(a.id_out, r);

  // 4. Summary.
  std::printf("scene        %s (%zu objects), environment %s\n", a.scene.c_str(), scene.objects().size(),
              scene.environment_description().c_str());
  std::printf("resolution   %dx%d\n", r.width, r.height);
  std::printf("spp          %d (seed %llu)\n", r.spp, static_cast<unsigned long long>(o.seed));
  std::printf("strategy     %s, integrator %s", to_string(o.strategy), to_string(o.integrator));
  if (o.integrator == IntegratorKind::Path) std::printf(" (max depth %d)", o.max_depth);
  std::printf(", heuristic %s\n", to_string(o.heuristic));
  std::printf("wall seconds %.3f (tables %.3f s; CPU %.3f s)\n", r.seconds, r.setup_seconds, r.cpu_seconds);
  std::printf("samples/s    %.4g\n", r.seconds > 0 ? double(r.samples) / r.seconds : 0.0);
  if (r.nonfinite_pixels > 0) std::printf("non-finite   %zu pixels set to 0\n", r.nonfinite_pixels);
  std::printf("wrote        %s\n", a.out.c_str());
}

const RegisterCommand reg{{"render", "Render a scene with one sampling strategy to a float OpenEXR",
                           [](CLI::App& sub) {
                             auto a = std::make_shared<RenderArgs>();
                             sub.add_option("--scene", a->scene, "fig1, fig5 or a JSON scene file (docs/scene-format.md)")->type_name("NAME|FILE")
                                 ->capture_default_str();
                             sub.add_option("--env", a->env,
                                            "environment map (EXR/HDR); default: the scene's (see docs/scene-format.md)")->type_name("FILE");
                             sub.add_option("--env-rotation", a->env_rotation, "rotation of --env about +Z, degrees")->type_name("DEG");
                             sub.add_option("--env-scale", a->env_scale, "radiance scale of --env")->type_name("FLOAT");
                             sub.add_option("--strategy", a->strategy, "bsdf, env, mis, mis-comp, product or oracle")->type_name("S")
                                 ->capture_default_str();
                             sub.add_option("--spp", a->spp, "samples per pixel")->type_name("INT")->capture_default_str();
                             sub.add_option("--seed", a->seed, "random seed")->type_name("INT")->capture_default_str();
                             sub.add_option("--width", a->width, "image width (0: the scene's)")->type_name("INT")->capture_default_str();
                             sub.add_option("--height", a->height, "image height (0: the scene's)")->type_name("INT")->capture_default_str();
                             sub.add_option("--threads", a->threads, "worker threads (0: all)")->type_name("INT")->capture_default_str();
                             sub.add_option("--integrator", a->integrator, "direct or path")->type_name("I")->capture_default_str();
                             sub.add_option("--heuristic", a->heuristic, "MIS heuristic: power or balance")->type_name("H")
                                 ->capture_default_str();
                             sub.add_option("--max-depth", a->max_depth, "path integrator: maximum bounces")->type_name("INT")
                                 ->capture_default_str();
                             sub.add_option("--oracle-res", a->oracle_res, "oracle: top cells per side")->type_name("INT")
                                 ->capture_default_str();
                             sub.add_option("--oracle-dirs", a->oracle_dirs, "oracle: BSDF evaluations per cell (square)")->type_name("INT")
                                 ->capture_default_str();
                             sub.add_option("--proxy-transform", a->proxy_transform,
                                            "product: proxy roughness transform (default: the library's)")->type_name("T");
                             sub.add_option("--proxy-min-alpha", a->proxy_min_alpha,
                                            "product: floor on the transformed proxy roughness (default: the library's)")->type_name("FLOAT");
                             sub.add_option("--env-mix", a->env_mix,
                                            "product: fraction of environment-only sampling mixed in (default: the library's)")->type_name("FLOAT");
                             sub.add_option("--out", a->out, "output OpenEXR file")->type_name("FILE.exr");
                             sub.add_option("--id-out", a->id_out, "also write the object-id AOV (first hit per pixel)")->type_name("FILE");
                             sub.add_flag("--quiet", a->quiet, "no progress bar");
                             sub.callback([a] { run(*a); });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
