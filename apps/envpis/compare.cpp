// envpis compare: renders a reference and every strategy at equal samples (and at equal time), measures
// relMSE per image and per object, the overhead of product over mis and a convergence series, and
// writes DIR/metrics.json, every image (EXR + tonemapped PNG + false-colour error map) and the report
// DIR/index.html (report/template.html, report/report.js, report/report.css; plots by report/plots.py).
//
// Method (DESIGN.md section 5):
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
#ifdef ENVPIS_HAVE_RENDER

#include <OpenImageIO/imageio.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdarg>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "command.h"
#include "metrics.h"
#include "options.h"
#include "envpis/envpis.h"
#include "render/render.h"
#include "render/scenes.h"

extern char** environ;

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace envpis::render;

constexpr std::uint64_t kRefSeedOffset = 1000003;
constexpr int kMaxSeeds = 64;
constexpr double kErrLog10Min = -5.0, kErrLog10Max = 1.0;  // false-colour range of the error maps

struct CompareArgs {
  SceneOptionArgs common{"direct"};
  std::string strategies = "mis,mis-comp,product,oracle";
  std::string spp = "16";
  std::string ref_spp = "1024";
  std::string ref_strategy = "mis";
  std::string ref_seed;
  std::string equal_time;
  std::string width = "0", height = "0";  // 0: half the scene camera's size
  std::string seed = "0";
  std::string seeds = "1";
  std::string repeats = "3";
  std::string cache_dir;
  std::string report_dir;
  std::string out;
  std::string firefly_log, firefly_factor;  // empty: no log; the factor's default is kFireflyFactor
  bool no_cache = false;
  bool no_convergence = false;
  bool no_plots = false;
  bool quiet = false;
};

// ---------------------------------------------------------------------------------------------------
// Option parsing

std::vector<Strategy> parse_strategy_list(const std::string& list) {
  std::vector<Strategy> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    item.erase(std::remove_if(item.begin(), item.end(), [](unsigned char c) { return std::isspace(c); }), item.end());
    if (item.empty()) throw Error("--strategies: empty name in '" + list + "'");
    Strategy s;
    try {
      s = parse_strategy(item);
    } catch (const std::exception&) {
      throw Error("--strategies: unknown strategy '" + item + "' (bsdf, env, mis, mis-comp, product, oracle)");
    }
    if (std::find(out.begin(), out.end(), s) != out.end())
      throw Error("--strategies: '" + item + "' is listed twice");
    out.push_back(s);
  }
  if (out.empty()) throw Error("--strategies must name at least one strategy");
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Images and metrics

struct Region {
  int id = -1;
  std::string name;
  std::size_t pixels = 0;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // bounding box of the object's pixels, inclusive
  double cx = 0, cy = 0;               // centroid (pixel centres)
};

struct Reference {
  int width = 0, height = 0, spp = 0;
  std::vector<float> rgb, variance;
  std::vector<int> object_id;
  double seconds = 0;
  std::uint64_t seed = 0;
  Strategy strategy = Strategy::Mis;
  bool cached = false;
};

constexpr double kFireflyFactor = 10;

/// --firefly-log's per-pixel thresholds: a sample is logged when its contribution divided by spp exceeds
/// factor * sqrt(R^2 + kRelEpsilon), R the reference pixel's channel average. That is the tail metric's
/// scale (metrics.h): at factor 10, one logged sample alone takes its pixel about 10x off.
FireflyLogOptions relative_firefly_log(const Reference& ref, int spp, double factor) {
  FireflyLogOptions log;
  const std::size_t npix = static_cast<std::size_t>(ref.width) * ref.height;
  log.pixel_threshold.resize(npix);
  for (std::size_t p = 0; p < npix; ++p) {
    const double R = (double(ref.rgb[p * 3]) + ref.rgb[p * 3 + 1] + ref.rgb[p * 3 + 2]) / 3;
    log.pixel_threshold[p] = static_cast<float>(factor * spp * std::sqrt(R * R + kRelEpsilon));
  }
  return log;
}

ImageMetrics measure_image(const RenderResult& r, const Reference& ref, const std::vector<Region>& regions) {
  std::vector<int> ids;
  for (const Region& g : regions) ids.push_back(g.id);
  return measure(NoisyImage{r.rgb, r.variance}, NoisyImage{ref.rgb, ref.variance}, ref.object_id, ids);
}

void write_png(const std::string& path, int w, int h, const std::vector<unsigned char>& rgb8) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error("cannot write '" + path + "': " + OIIO::geterror());
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb8.data()) || !out->close())
    throw Error("cannot write '" + path + "': " + out->geterror());
}

/// Exposure for the PNGs, from the reference: its median (R+G+B)/3 over object pixels maps to 0.5 on
/// the curve 1 - exp(-k x) (a smooth shoulder keeps the sun's reflections from clipping flat).
double tonemap_exposure(const Reference& ref) {
  std::vector<float> v;
  const std::size_t npix = static_cast<std::size_t>(ref.width) * ref.height;
  for (std::size_t p = 0; p < npix; ++p)
    if (ref.object_id[p] >= 0) v.push_back((ref.rgb[p * 3] + ref.rgb[p * 3 + 1] + ref.rgb[p * 3 + 2]) / 3);
  if (v.empty())
    for (std::size_t p = 0; p < npix; ++p) v.push_back((ref.rgb[p * 3] + ref.rgb[p * 3 + 1] + ref.rgb[p * 3 + 2]) / 3);
  if (v.empty()) return 1;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  const double median = v[v.size() / 2];
  return median > 1e-6 ? std::log(2.0) / median : 1.0;
}

unsigned char srgb8(double linear) {
  const double x = std::clamp(linear, 0.0, 1.0);
  const double s = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(s * 255));
}

void write_tonemapped_png(const std::string& path, int w, int h, const std::vector<float>& rgb, double k) {
  std::vector<unsigned char> px(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const double x = std::isfinite(rgb[i]) ? std::max(0.0f, rgb[i]) : 0.0;
    px[i] = srgb8(1 - std::exp(-k * x));
  }
  write_png(path, w, h, px);
}

/// Inferno-like colour map (9 stops of matplotlib's inferno), also used for the report's legend.
const std::vector<std::array<int, 3>>& colormap_stops() {
  static const std::vector<std::array<int, 3>> stops{{0, 0, 4},      {31, 12, 72},   {85, 15, 109},
                                                      {136, 34, 106}, {186, 54, 85},  {227, 89, 51},
                                                      {249, 140, 10}, {249, 201, 50}, {252, 255, 164}};
  return stops;
}

void write_error_png(const std::string& path, int w, int h, const std::vector<float>& per_pixel) {
  const auto& stops = colormap_stops();
  std::vector<unsigned char> px(per_pixel.size() * 3);
  for (std::size_t p = 0; p < per_pixel.size(); ++p) {
    const double e = per_pixel[p];
    double t = e > 0 ? (std::log10(e) - kErrLog10Min) / (kErrLog10Max - kErrLog10Min) : 0.0;
    t = std::clamp(std::isfinite(t) ? t : 1.0, 0.0, 1.0) * double(stops.size() - 1);
    const std::size_t i = std::min(stops.size() - 2, static_cast<std::size_t>(t));
    const double f = t - double(i);
    for (int c = 0; c < 3; ++c)
      px[p * 3 + c] = static_cast<unsigned char>(std::lround(stops[i][c] * (1 - f) + stops[i + 1][c] * f));
  }
  write_png(path, w, h, px);
}

// ---------------------------------------------------------------------------------------------------
// The reference cache: <cache>/ref-<hash>.exr (R, G, B, variance) + ref-<hash>.json (the key).

std::string fnv1a_hex(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

json file_identity(const std::string& path) {
  std::error_code ec;
  const fs::path canon = fs::weakly_canonical(fs::path(path), ec);
  struct stat st {};
  json j;
  j["path"] = ec ? path : canon.string();
  if (::stat(path.c_str(), &st) == 0) {
    j["size"] = static_cast<std::uint64_t>(st.st_size);
    j["mtime"] = static_cast<std::int64_t>(st.st_mtime);
  }
  return j;
}

std::string default_cache_dir() {
  if (const char* e = std::getenv("ENVPIS_CACHE_DIR"); e && *e) return e;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return (fs::path(x) / "envpis" / "references").string();
  if (const char* h = std::getenv("HOME"); h && *h) return (fs::path(h) / ".cache" / "envpis" / "references").string();
  return "";
}

std::optional<Reference> load_cached_reference(const std::string& dir, const json& key) {
  const std::string base = (fs::path(dir) / ("ref-" + fnv1a_hex(key.dump()))).string();
  std::ifstream in(base + ".json");
  if (!in) return std::nullopt;
  json side;
  try {
    in >> side;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (!side.contains("key") || side["key"] != key) return std::nullopt;
  auto img = OIIO::ImageInput::open(base + ".exr");
  if (!img) return std::nullopt;
  const OIIO::ImageSpec& spec = img->spec();
  const int W = key["width"].get<int>(), H = key["height"].get<int>();
  if (spec.width != W || spec.height != H || spec.nchannels != 4) return std::nullopt;
  std::vector<float> px(static_cast<std::size_t>(W) * H * 4);
  if (!img->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, px.data())) return std::nullopt;
  Reference r;
  r.width = W;
  r.height = H;
  r.spp = key["spp"].get<int>();
  r.seed = key["seed"].get<std::uint64_t>();
  r.seconds = side.value("seconds", 0.0);
  r.cached = true;
  const std::size_t npix = static_cast<std::size_t>(W) * H;
  r.rgb.resize(npix * 3);
  r.variance.resize(npix);
  for (std::size_t p = 0; p < npix; ++p) {
    for (int c = 0; c < 3; ++c) r.rgb[p * 3 + c] = px[p * 4 + c];
    r.variance[p] = px[p * 4 + 3];
  }
  return r;
}

void store_cached_reference(const std::string& dir, const json& key, const Reference& r) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create cache directory '" + dir + "': " + ec.message());
  const std::string base = (fs::path(dir) / ("ref-" + fnv1a_hex(key.dump()))).string();
  const std::string tmp = base + ".tmp." + std::to_string(::getpid()) + ".exr";
  auto out = OIIO::ImageOutput::create(tmp);
  if (!out) throw Error("cannot write '" + tmp + "': " + OIIO::geterror());
  OIIO::ImageSpec spec(r.width, r.height, 4, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"R", "G", "B", "variance"};
  spec.alpha_channel = -1;
  spec.attribute("compression", "zip");
  const std::size_t npix = static_cast<std::size_t>(r.width) * r.height;
  std::vector<float> px(npix * 4);
  for (std::size_t p = 0; p < npix; ++p) {
    for (int c = 0; c < 3; ++c) px[p * 4 + c] = r.rgb[p * 3 + c];
    px[p * 4 + 3] = r.variance[p];
  }
  if (!out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, px.data()) || !out->close())
    throw Error("cannot write '" + tmp + "': " + out->geterror());
  fs::rename(tmp, base + ".exr", ec);
  if (ec) throw Error("cannot write '" + base + ".exr': " + ec.message());
  json side;
  side["key"] = key;
  side["seconds"] = r.seconds;
  side["file"] = fs::path(base + ".exr").filename().string();
  std::ofstream(base + ".json") << side.dump(2) << "\n";
}

// ---------------------------------------------------------------------------------------------------
// Running the plotting script

/// Runs argv (argv[0] looked up on PATH); returns the exit status, 127 when it could not start.
int run_process(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ) != 0) return 127;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 127;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

/// The report's template, script and plotting script: --report-dir, $ENVPIS_REPORT_DIR, the source
/// tree this binary was built from, or <prefix>/share/envpis/report next to an installed binary.
std::string find_report_dir(const std::string& option) {
  auto ok = [](const fs::path& d) {
    std::error_code ec;
    return fs::is_regular_file(d / "template.html", ec);
  };
  if (!option.empty()) {
    if (!ok(option)) throw Error("--report-dir '" + option + "' has no template.html");
    return option;
  }
  std::vector<fs::path> candidates;
  if (const char* e = std::getenv("ENVPIS_REPORT_DIR"); e && *e) candidates.emplace_back(e);
  candidates.push_back(fs::path(__FILE__).parent_path().parent_path().parent_path() / "report");
  const std::string exe = executable_dir();
  if (!exe.empty()) candidates.push_back(fs::path(exe).parent_path() / "share" / "envpis" / "report");
  for (const auto& c : candidates)
    if (ok(c)) return c.string();
  return "";
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error("cannot read '" + p.string() + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  for (std::size_t pos = 0; (pos = s.find(from, pos)) != std::string::npos; pos += to.size()) s.replace(pos, from.size(), to);
}

/// JSON safe to embed inside <script type="application/json">: no "</" sequences.
std::string json_for_script(const json& j) {
  std::string s = j.dump();
  replace_all(s, "</", "<\\/");
  replace_all(s, "<!--", "<\\!--");
  return s;
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// ---------------------------------------------------------------------------------------------------

struct Measured {
  Strategy strategy;
  int spp = 0;
  double seconds = 0;      // wall, minimum over the runs
  double cpu_seconds = 0;  // process CPU seconds (all threads), minimum over the runs
  std::vector<double> seconds_runs;
  std::size_t nan_count = 0;
  ImageMetrics metrics;                  // of the first seed, whose image is written and shown
  std::vector<ImageMetrics> more_seeds;  // of seeds --seed + 1, ... (--seeds > 1), without per_pixel
  std::string stem;  // images/<stem>.{exr,png}, images/<stem>-error.png
};

/// One number of each seed's metrics, in seed order.
template <class F>
std::vector<double> over_seeds(const Measured& m, F f) {
  std::vector<double> v{double(f(m.metrics))};
  for (const ImageMetrics& x : m.more_seeds) v.push_back(double(f(x)));
  return v;
}

/// The relMSE that compares strategies (and gives the efficiency): the median over the seeds.
double headline_relmse(const Measured& m) {
  return median(over_seeds(m, [](const ImageMetrics& x) { return x.image.relmse; }));
}

class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), t0_(std::chrono::steady_clock::now()) {}
  void line(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
    if (quiet_) return;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    std::fprintf(stderr, "[%6.1fs] ", t);
    va_list ap;
    va_start(ap, fmt);
    std::vfprintf(stderr, fmt, ap);
    va_end(ap);
    std::fputc('\n', stderr);
  }
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }

 private:
  bool quiet_;
  std::chrono::steady_clock::time_point t0_;
};

json num(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }
/// A pixel count, or the median of an even number of counts (which may end in .5).
json count_json(double x) { return x == std::floor(x) ? json(static_cast<std::uint64_t>(x)) : json(x); }

/// Per object: relMSE, its standard error and the mean; `with_z` adds the bias z-score.
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

void run(const CompareArgs& a, const std::string& command_line) {
  // 1. Options, all checked before anything slow.
  const std::vector<Strategy> strategies = parse_strategy_list(a.strategies);
  RenderOptions base;
  a.common.apply(base);
  base.width = static_cast<int>(parse_integer("--width", a.width, 0, kMaxImageSide));
  base.height = static_cast<int>(parse_integer("--height", a.height, 0, kMaxImageSide));
  a.common.map_options();
  const int spp = static_cast<int>(parse_integer("--spp", a.spp, 1, kMaxSpp));
  const int ref_spp = static_cast<int>(parse_integer("--ref-spp", a.ref_spp, 1, kMaxSpp));
  if (ref_spp < spp) throw Error("--ref-spp (" + a.ref_spp + ") must be at least --spp (" + a.spp + ")");
  const Strategy ref_strategy = [&] {
    try {
      return parse_strategy(a.ref_strategy);
    } catch (const std::exception&) {
      throw Error("--ref-strategy: unknown strategy '" + a.ref_strategy + "'");
    }
  }();
  const std::uint64_t seed = static_cast<std::uint64_t>(parse_integer("--seed", a.seed, 0, INT64_MAX / 2));
  const int nseeds = static_cast<int>(parse_integer("--seeds", a.seeds, 1, kMaxSeeds));
  const std::uint64_t ref_seed =
      a.ref_seed.empty() ? seed + kRefSeedOffset : static_cast<std::uint64_t>(parse_integer("--ref-seed", a.ref_seed, 0, INT64_MAX));
  if (ref_seed >= seed && ref_seed - seed < static_cast<std::uint64_t>(nseeds))
    throw Error("--ref-seed " + std::to_string(ref_seed) + " is one of the measured seeds " + std::to_string(seed) + ".." +
                std::to_string(seed + nseeds - 1) + " (--seed, --seeds): the reference's noise must be independent");
  const int repeats = static_cast<int>(parse_integer("--repeats", a.repeats, 1, 100));
  std::optional<double> equal_time;
  bool equal_time_auto = false;
  if (!a.equal_time.empty()) {
    if (a.equal_time == "auto") {
      equal_time_auto = true;
    } else {
      const double t = parse_number("--equal-time", a.equal_time);
      if (!(t > 0)) throw Error("--equal-time must be positive seconds or 'auto', got " + a.equal_time);
      equal_time = t;
    }
  }
  {
    RenderOptions check = base;
    check.spp = ref_spp;
    validate(check);
  }
  double firefly_factor = kFireflyFactor;
  if (!a.firefly_factor.empty()) {
    if (a.firefly_log.empty()) throw Error("--firefly-factor needs --firefly-log");
    firefly_factor = parse_number_in("--firefly-factor", a.firefly_factor, 0, 1e30, "> 0");
    if (!(firefly_factor > 0)) throw Error("--firefly-factor: must be > 0, got '" + a.firefly_factor + "'");
  }
  if (!a.firefly_log.empty()) {
    std::error_code ec;
    if (fs::exists(a.firefly_log, ec) && !fs::is_directory(a.firefly_log, ec))
      throw Error("--firefly-log '" + a.firefly_log + "' exists and is not a directory");
    fs::create_directories(a.firefly_log, ec);
    if (ec) throw Error("cannot create --firefly-log '" + a.firefly_log + "': " + ec.message());
    check_writable_file((fs::path(a.firefly_log) / "fireflies-mis.csv").string(), "--firefly-log");
  }
  if (a.out.empty()) throw Error("--out is required (the output directory)");
  const fs::path out(a.out);
  {
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_directory(out, ec)) throw Error("--out '" + a.out + "' exists and is not a directory");
    fs::create_directories(out / "images", ec);
    if (ec) throw Error("cannot create --out '" + a.out + "': " + ec.message());
    const fs::path probe = out / ".envpis-write-test";
    std::FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f) throw Error("cannot write into --out '" + a.out + "': " + std::strerror(errno));
    std::fclose(f);
    fs::remove(probe, ec);
  }
  const std::string report_dir = find_report_dir(a.report_dir);

  Progress progress(a.quiet);

  // 2. Scene and environment.
  const Scene scene = a.common.load_scene("compare", nullptr);
  if (!scene.has_environment() || scene.environment().is_black())
    throw Error("the environment (" + scene.environment_description() +
                ") has no positive radiance: every strategy renders a black image, there is nothing to compare");
  // Default size: half the scene's (a fast comparison; fig1: 384x64), keeping its aspect ratio.
  const int W = base.width > 0 ? base.width
                               : base.height > 0 ? std::max(1, static_cast<int>(std::lround(double(base.height) *
                                                                                        scene.camera().width /
                                                                                        scene.camera().height)))
                                                 : std::max(1, scene.camera().width / 2);
  const int H = base.height > 0 ? base.height
                                : base.width > 0 ? std::max(1, static_cast<int>(std::lround(double(base.width) *
                                                                                         scene.camera().height /
                                                                                         scene.camera().width)))
                                                 : std::max(1, scene.camera().height / 2);
  base.width = W;
  base.height = H;
  const int threads_used = base.threads > 0 ? base.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  progress.line("scene %s, %dx%d, environment %s, integrator %s, sampler %s, %d threads", a.common.scene.c_str(),
                W, H, scene.environment_description().c_str(), to_string(base.integrator), to_string(base.sampler),
                threads_used);

  // 3. Tables, built once per strategy and shared by every render of it.
  std::map<Strategy, StrategyTables> tables;
  auto tables_for = [&](Strategy s) -> const StrategyTables& {
    auto it = tables.find(s);
    if (it == tables.end())
      it = tables.emplace(s, StrategyTables::build(scene.environment(), s, base.oracle, base.product,
                                                   base.light_table)).first;
    return it->second;
  };
  // A progress bar on a terminal for renders that take a while (the reference, the oracle).
  const bool bar = !a.quiet && isatty(STDERR_FILENO);
  auto do_render = [&](Strategy s, int n, std::uint64_t sd, const std::string& label,
                       const FireflyLogOptions* log = nullptr) {
    RenderOptions o = base;
    o.firefly_log = log;
    o.strategy = s;
    o.spp = n;
    o.seed = sd;
    o.tables = &tables_for(s);
    const auto t0 = std::chrono::steady_clock::now();
    if (bar && !label.empty())
      o.progress = [&label, t0](double f) {
        if (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2)) return;
        std::fprintf(stderr, "\r  %s: %3d%%", label.c_str(), static_cast<int>(f * 100 + 0.5));
        std::fflush(stderr);
      };
    RenderResult r = envpis::render::render(scene, o);
    if (bar && !label.empty() && std::chrono::steady_clock::now() - t0 >= std::chrono::seconds(2))
      std::fprintf(stderr, "\r%*s\r", static_cast<int>(label.size()) + 10, "");
    return r;
  };

  // 4. Reference (cached).
  json key;
  key["version"] = kVersion;
  key["scene"] = is_builtin_scene(a.common.scene) ? json(a.common.scene) : file_identity(a.common.scene);
  key["environment"] = a.common.env.empty() ? json(scene.environment_description()) : file_identity(a.common.env);
  if (!a.common.env.empty()) key["environment_transform"] = {a.common.env_rotation, a.common.env_scale};
  // How the map is read changes the image whichever map it is (--env or the scene's), and references
  // cached before the lat-long orientation became an option have no such entry: they do not match.
  if (scene.has_environment())
    key["environment_lookup"] = {to_string(scene.environment().orientation()), to_string(scene.environment().filter())};
  key["width"] = W;
  key["height"] = H;
  key["integrator"] = to_string(base.integrator);
  key["max_depth"] = base.integrator == IntegratorKind::Path ? base.max_depth : 1;
  key["heuristic"] = to_string(base.heuristic);
  key["sampler"] = to_string(base.sampler);
  key["strategy"] = to_string(ref_strategy);
  key["spp"] = ref_spp;
  key["seed"] = ref_seed;
  if (ref_strategy == Strategy::Oracle) key["oracle"] = {base.oracle.resolution, base.oracle.directions};
  if (ref_strategy != Strategy::Bsdf && ref_strategy != Strategy::Oracle) key["top"] = base.light_table.top_resolution;
  if (ref_strategy != Strategy::Bsdf) {
    key["peak_ratio"] = base.light_table.peak_ratio;
    key["fine"] = base.light_table.fine_resolution;
  }
  if ((ref_strategy == Strategy::Product || ref_strategy == Strategy::Oracle) && !scene.proxy_closed_surfaces())
    key["closed_surfaces"] = false;
  if (ref_strategy == Strategy::Product)
    key["product"] = {static_cast<int>(base.product.proxy.transform), base.product.proxy.min_alpha,
                      base.product.proxy.max_alpha, base.product.env_mix, base.product.env_floor};
  const std::string cache_dir = a.no_cache ? "" : (a.cache_dir.empty() ? default_cache_dir() : a.cache_dir);
  std::optional<Reference> ref_opt;
  if (!cache_dir.empty()) ref_opt = load_cached_reference(cache_dir, key);
  if (ref_opt) {
    progress.line("reference: %s @ %d spp (seed %llu), cached in %s", to_string(ref_strategy), ref_spp,
                  static_cast<unsigned long long>(ref_seed), cache_dir.c_str());
  } else {
    progress.line("reference: %s @ %d spp (seed %llu) ...", to_string(ref_strategy), ref_spp,
                  static_cast<unsigned long long>(ref_seed));
    RenderResult rr = do_render(ref_strategy, ref_spp, ref_seed, "reference");
    Reference r;
    r.width = rr.width;
    r.height = rr.height;
    r.spp = rr.spp;
    r.rgb = std::move(rr.rgb);
    r.variance = std::move(rr.variance);
    r.seconds = rr.seconds;
    r.seed = ref_seed;
    progress.line("reference: %.2f s", r.seconds);
    if (rr.nonfinite_pixels > 0)
      std::fprintf(stderr, "envpis compare: warning: %zu non-finite reference pixels set to 0\n", rr.nonfinite_pixels);
    if (!cache_dir.empty()) {
      try {
        store_cached_reference(cache_dir, key, r);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "envpis compare: warning: reference not cached: %s\n", e.what());
      }
    }
    ref_opt = std::move(r);
  }
  Reference& ref = *ref_opt;
  ref.strategy = ref_strategy;

  // 5. Equal spp (timing repeated, minimum kept), which also gives the object-id AOV and the calibration.
  // The firefly log, if asked for, sees these first-seed renders (a log does not change the image).
  std::optional<FireflyLogOptions> firefly_log;
  if (!a.firefly_log.empty()) firefly_log = relative_firefly_log(ref, spp, firefly_factor);
  std::vector<Measured> eq_spp;
  std::vector<Region> regions;
  std::vector<RenderResult> eq_images;
  for (Strategy s : strategies) {
    tables_for(s);
    Measured m;
    m.strategy = s;
    m.spp = spp;
    m.stem = std::string("spp-") + to_string(s);
    RenderResult r = do_render(s, spp, seed, std::string("equal spp: ") + to_string(s),
                               firefly_log ? &*firefly_log : nullptr);
    if (firefly_log) {
      const std::string csv = (fs::path(a.firefly_log) / (std::string("fireflies-") + to_string(s) + ".csv")).string();
      write_firefly_csv(csv, r.fireflies);
      progress.line("firefly log: %-8s %zu samples over %g x the reference -> %s", to_string(s), r.fireflies.size(),
                    firefly_factor, csv.c_str());
      if (r.fireflies_dropped > 0)
        std::fprintf(stderr, "envpis compare: warning: %zu more %s fireflies not kept (raise --firefly-factor)\n",
                     r.fireflies_dropped, to_string(s));
    }
    m.seconds_runs.push_back(r.seconds);
    m.seconds = r.seconds;
    m.cpu_seconds = r.cpu_seconds;
    m.nan_count = r.nonfinite_pixels;
    if (regions.empty()) {
      ref.object_id = r.object_id;
      std::vector<Region> all(scene.objects().size());
      for (std::size_t i = 0; i < all.size(); ++i) {
        all[i].id = static_cast<int>(i);
        all[i].name = scene.objects()[i].name;
        all[i].x0 = W;
        all[i].y0 = H;
        all[i].x1 = all[i].y1 = -1;
      }
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          const int id = r.object_id[static_cast<std::size_t>(y) * W + x];
          if (id < 0 || static_cast<std::size_t>(id) >= all.size()) continue;
          Region& g = all[static_cast<std::size_t>(id)];
          ++g.pixels;
          g.x0 = std::min(g.x0, x);
          g.y0 = std::min(g.y0, y);
          g.x1 = std::max(g.x1, x);
          g.y1 = std::max(g.y1, y);
          g.cx += x + 0.5;
          g.cy += y + 0.5;
        }
      for (Region& g : all)
        if (g.pixels > 0) {
          g.cx /= double(g.pixels);
          g.cy /= double(g.pixels);
          regions.push_back(g);
        }
    }
    progress.line("equal spp: %-8s %d spp  %.3f s", to_string(s), spp, m.seconds);
    eq_images.push_back(std::move(r));
    eq_spp.push_back(std::move(m));
  }
  // Timing repeats, interleaved across strategies (so a change in the machine's load hits all of them),
  // only for the fast renders: a timing under a couple of seconds is the noisy one. Images are
  // deterministic, so only the times are kept; each strategy's time is its minimum.
  for (int i = 1; i < repeats; ++i)
    for (Measured& m : eq_spp) {
      if (m.seconds_runs.front() >= 2.0) continue;
      const RenderResult again = do_render(m.strategy, spp, seed, "");
      m.seconds_runs.push_back(again.seconds);
      m.seconds = std::min(m.seconds, again.seconds);
      m.cpu_seconds = std::min(m.cpu_seconds, again.cpu_seconds);
    }
  if (repeats > 1)
    for (const Measured& m : eq_spp)
      progress.line("equal spp: %-8s %.3f s (min of %zu runs)", to_string(m.strategy), m.seconds, m.seconds_runs.size());
  for (std::size_t i = 0; i < eq_spp.size(); ++i)
    eq_spp[i].metrics = measure_image(eq_images[i], ref, regions);
  // Seeds --seed + 1, ...: their metrics only (the images and the timing are the first seed's).
  auto measure_more_seeds = [&](Measured& m, const std::string& what) {
    for (int k = 1; k < nseeds; ++k) {
      const RenderResult r = do_render(m.strategy, m.spp, seed + k,
                                       what + ": " + to_string(m.strategy) + " seed " + std::to_string(seed + k));
      m.more_seeds.push_back(measure_image(r, ref, regions));
      m.more_seeds.back().per_pixel = std::vector<float>();  // only the first seed's error map is written
    }
    if (nseeds > 1)
      progress.line("%s: %-8s relMSE median %.4g over %d seeds", what.c_str(), to_string(m.strategy), headline_relmse(m), nseeds);
  };
  for (Measured& m : eq_spp) measure_more_seeds(m, "equal spp");

  // 6. Overhead of product over mis at equal spp (same run, same threads).
  auto find_eq = [&](Strategy s) -> const Measured* {
    for (const auto& m : eq_spp)
      if (m.strategy == s) return &m;
    return nullptr;
  };
  json overhead = nullptr;
  if (const Measured *p = find_eq(Strategy::Product), *m = find_eq(Strategy::Mis); p && m && m->seconds > 0) {
    overhead = {{"ratio", p->seconds / m->seconds},
                {"product_seconds", p->seconds},
                {"mis_seconds", m->seconds},
                {"ratio_cpu", m->cpu_seconds > 0 ? json(p->cpu_seconds / m->cpu_seconds) : json(nullptr)},
                {"product_cpu_seconds", p->cpu_seconds},
                {"mis_cpu_seconds", m->cpu_seconds},
                {"spp", spp},
                {"threads", threads_used}};
    progress.line("overhead: time(product) / time(mis) = %.3f (CPU time: %.3f)", p->seconds / m->seconds,
                  m->cpu_seconds > 0 ? p->cpu_seconds / m->cpu_seconds : 0.0);
  }

  // 7. Convergence series (prefixes of the equal-spp renders: same seed).
  json convergence = json::object();
  if (!a.no_convergence) {
    std::vector<int> points;
    for (int n = 1; n < spp; n *= 2) points.push_back(n);
    for (std::size_t i = 0; i < eq_spp.size(); ++i) {
      const Strategy s = eq_spp[i].strategy;
      json series = json::array();
      for (int n : points) {
        RenderResult r = do_render(s, n, seed, std::string("convergence: ") + to_string(s) + " @ " + std::to_string(n));
        const ImageMetrics mm = measure_image(r, ref, regions);
        series.push_back({{"spp", n}, {"seconds", r.seconds}, {"relmse", mm.image.relmse}, {"regions", regions_json(regions, mm, false)}});
      }
      series.push_back({{"spp", spp},
                        {"seconds", eq_spp[i].seconds},
                        {"relmse", eq_spp[i].metrics.image.relmse},
                        {"regions", regions_json(regions, eq_spp[i].metrics, false)}});
      convergence[to_string(s)] = series;
      progress.line("convergence: %-8s %zu points", to_string(s), points.size() + 1);
    }
  }

  // 8. Equal time: calibration = the equal-spp render (seconds per spp), then the spp that fits.
  std::vector<Measured> eq_time;
  std::vector<RenderResult> time_images;
  double budget = 0;
  if (equal_time || equal_time_auto) {
    if (equal_time_auto) {
      const Measured* m = find_eq(Strategy::Mis);
      budget = (m ? m : &eq_spp.front())->seconds;  // mis's time, or the first strategy's without mis
    } else {
      budget = *equal_time;
    }
    for (const Measured& e : eq_spp) {
      const double per_spp = std::max(e.seconds, 1e-9) / e.spp;
      const int n = static_cast<int>(std::clamp(std::floor(budget / per_spp + 0.5), 1.0, double(kMaxSpp)));
      Measured m;
      m.strategy = e.strategy;
      m.spp = n;
      m.stem = std::string("time-") + to_string(e.strategy);
      RenderResult r = do_render(e.strategy, n, seed, std::string("equal time: ") + to_string(e.strategy));
      m.seconds_runs.push_back(r.seconds);
      m.seconds = r.seconds;
      m.cpu_seconds = r.cpu_seconds;
      m.nan_count = r.nonfinite_pixels;
      m.metrics = measure_image(r, ref, regions);
      progress.line("equal time: %-8s %d spp  %.3f s (budget %.3f s)", to_string(e.strategy), n, r.seconds, budget);
      measure_more_seeds(m, "equal time");
      time_images.push_back(std::move(r));
      eq_time.push_back(std::move(m));
    }
  }

  // 9. Images.
  const fs::path img = out / "images";
  const double exposure = tonemap_exposure(ref);
  {
    RenderResult rr;
    rr.width = W;
    rr.height = H;
    rr.spp = ref.spp;
    rr.strategy = ref.strategy;
    rr.integrator = base.integrator;
    rr.rgb = ref.rgb;
    rr.object_id = ref.object_id;
    write_exr((img / "reference.exr").string(), rr);
    write_object_id((img / "object-id.exr").string(), rr);
    write_tonemapped_png((img / "reference.png").string(), W, H, ref.rgb, exposure);
  }
  auto write_set = [&](const std::vector<Measured>& ms, const std::vector<RenderResult>& rs) {
    for (std::size_t i = 0; i < ms.size(); ++i) {
      write_exr((img / (ms[i].stem + ".exr")).string(), rs[i]);
      write_tonemapped_png((img / (ms[i].stem + ".png")).string(), W, H, rs[i].rgb, exposure);
      write_error_png((img / (ms[i].stem + "-error.png")).string(), W, H, ms[i].metrics.per_pixel);
    }
  };
  write_set(eq_spp, eq_images);
  write_set(eq_time, time_images);

  // 10. metrics.json.
  json j;
  j["tool"] = "envpis compare";
  j["version"] = kVersion;
  j["command"] = command_line;
  {
    const std::time_t now = std::time(nullptr);
    char buf[64];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    j["date"] = buf;
  }
  j["scene"] = a.common.scene;
  j["environment"] = a.common.env.empty() ? scene.environment_description() : a.common.env;
  j["integrator"] = to_string(base.integrator);
  if (base.integrator == IntegratorKind::Path) j["max_depth"] = base.max_depth;
  j["heuristic"] = to_string(base.heuristic);
  j["sampler"] = to_string(base.sampler);
  j["width"] = W;
  j["height"] = H;
  j["seed"] = seed;
  j["seeds"] = json::array();
  for (int k = 0; k < nseeds; ++k) j["seeds"].push_back(seed + k);
  j["threads"] = threads_used;
  j["hardware_threads"] = std::thread::hardware_concurrency();
  j["relmse_definition"] = "mean over pixels and channels of (I - R)^2 / (R^2 + 0.01)";
  j["efficiency_definition"] = "1 / (relmse * seconds), seconds = wall time of the sampling loop";
  j["tail_definition"] = "per-pixel relative squared error e = mean over channels of (I - R)^2 / (R^2 + 0.01); "
                         "max_rel_sq_error = the largest e; pixels_over_10x = the number of pixels with e > 100";
  j["seeds_definition"] = "each strategy is rendered once per seed in `seeds`; relmse (= relmse_median), efficiency, "
                          "max_rel_sq_error and pixels_over_10x are medians over the seeds, _min/_max/_worst their "
                          "spread, _seeds the values per seed; images, relmse_stderr, mean, z, nan_count, seconds "
                          "and convergence are the first seed's";
  j["product_options"] = {{"proxy_transform", static_cast<int>(base.product.proxy.transform)},
                          {"proxy_min_alpha", base.product.proxy.min_alpha},
                          {"proxy_max_alpha", base.product.proxy.max_alpha},
                          {"env_mix", base.product.env_mix},
                          {"env_floor", base.product.env_floor}};
  if (!a.common.proxy_transform.empty()) j["product_options"]["proxy_transform_name"] = a.common.proxy_transform;
  j["oracle_options"] = {{"resolution", base.oracle.resolution}, {"directions", base.oracle.directions}};
  j["top_resolution"] = base.light_table.top_resolution;
  j["fine_resolution"] = base.light_table.fine_resolution;
  j["peak_ratio"] = base.light_table.peak_ratio;
  j["closed_surfaces"] = scene.proxy_closed_surfaces();
  if (!a.common.env.empty())
    j["environment_transform"] = {{"rotation_degrees", parse_number("--env-rotation", a.common.env_rotation)},
                                  {"scale", parse_number("--env-scale", a.common.env_scale)}};
  if (scene.has_environment())
    j["environment_lookup"] = {{"orientation", to_string(scene.environment().orientation())},
                               {"filter", to_string(scene.environment().filter())}};
  json tj = json::object();
  for (const auto& [s, t] : tables) tj[to_string(s)] = t.build_seconds;
  j["table_seconds"] = tj;
  j["reference"] = {{"strategy", to_string(ref.strategy)},
                    {"spp", ref.spp},
                    {"seed", ref.seed},
                    {"seconds", ref.seconds},
                    {"cached", ref.cached},
                    {"cache_dir", cache_dir},
                    {"relmse_floor", reference_floor(NoisyImage{ref.rgb, ref.variance})},
                    {"exr", "images/reference.exr"},
                    {"png", "images/reference.png"},
                    {"object_id_exr", "images/object-id.exr"}};
  json rj = json::array();
  for (const auto& r : regions)
    rj.push_back({{"id", r.id},
                  {"name", r.name},
                  {"pixels", r.pixels},
                  {"bbox", {r.x0, r.y0, r.x1 + 1, r.y1 + 1}},
                  {"centroid", {r.cx, r.cy}}});
  j["regions"] = rj;
  json es = json::array();
  for (const auto& m : eq_spp) es.push_back(measured_json(m, regions));
  j["equal_spp"] = {{"spp", spp}, {"strategies", es}};
  if (!eq_time.empty()) {
    json et = json::array();
    for (const auto& m : eq_time) et.push_back(measured_json(m, regions));
    j["equal_time"] = {{"budget_seconds", budget}, {"budget", equal_time_auto ? "auto (time of mis at equal spp)" : "given"},
                       {"strategies", et}};
  } else {
    j["equal_time"] = nullptr;
  }
  j["overhead"] = overhead;
  j["convergence"] = convergence;
  {
    json stops = json::array();
    for (const auto& s : colormap_stops()) stops.push_back({s[0], s[1], s[2]});
    j["error_map"] = {{"quantity", "mean over channels of (I - R)^2 / (R^2 + 0.01)"},
                      {"log10_min", kErrLog10Min},
                      {"log10_max", kErrLog10Max},
                      {"colormap", stops}};
  }
  j["tonemap"] = {{"curve", "1 - exp(-k x), then sRGB"}, {"k", exposure}};
  const fs::path metrics_path = out / "metrics.json";
  auto write_metrics = [&] { std::ofstream(metrics_path) << j.dump(2) << "\n"; };
  write_metrics();

  // 11. Plots (report/plots.py with matplotlib) and the report.
  std::string plots_problem;
  if (a.no_plots) {
    plots_problem = "plots disabled (--no-plots)";
  } else if (report_dir.empty()) {
    plots_problem = "report/plots.py not found (set ENVPIS_REPORT_DIR or --report-dir)";
  } else {
    std::vector<std::string> pythons;
    if (const char* p = std::getenv("ENVPIS_PYTHON"); p && *p) pythons.emplace_back(p);
    pythons.emplace_back("/usr/bin/python3");  // Debian's, where python3-matplotlib lives
    pythons.emplace_back("python3");
    const fs::path manifest = out / "plots" / "manifest.json";
    std::error_code ec;
    fs::remove(manifest, ec);
    int status = 127;
    for (const auto& py : pythons) {
      if (py.find('/') != std::string::npos && !fs::exists(py, ec)) continue;
      status = run_process({py, (fs::path(report_dir) / "plots.py").string(), metrics_path.string()});
      if (status == 0 || (status != 3 && status != 127)) break;  // 3: no matplotlib, 127: no python: try the next
    }
    if (status == 0 && fs::exists(manifest, ec)) {
      try {
        std::ifstream in(manifest);
        json pm;
        in >> pm;
        j["plots"] = pm;
      } catch (const std::exception& e) {
        plots_problem = std::string("plots manifest unreadable: ") + e.what();
      }
    } else if (status == 3 || status == 127) {
      plots_problem = "python3 with matplotlib not found (install python3-matplotlib)";
    } else {
      plots_problem = "report/plots.py failed (exit status " + std::to_string(status) + ")";
    }
  }
  if (!plots_problem.empty()) {
    j["plots"] = nullptr;
    j["plots_unavailable"] = plots_problem;
    if (!a.no_plots)
      std::fprintf(stderr, "envpis compare: warning: %s; images and metrics.json are written, the report has no plots\n",
                   plots_problem.c_str());
  }
  write_metrics();

  std::string html;
  if (!report_dir.empty()) {
    html = read_text(fs::path(report_dir) / "template.html");
    replace_all(html, "{{STYLE}}", read_text(fs::path(report_dir) / "report.css"));
    replace_all(html, "{{SCRIPT}}", read_text(fs::path(report_dir) / "report.js"));
    replace_all(html, "{{TITLE}}", html_escape("envpis compare: " + a.common.scene + " under " +
                                               fs::path(j["environment"].get<std::string>()).filename().string()));
    replace_all(html, "{{METRICS_JSON}}", json_for_script(j));
  } else {
    std::fprintf(stderr, "envpis compare: warning: report/template.html not found; writing a minimal index.html\n");
    html = "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>envpis compare</title></head><body>"
           "<h1>envpis compare</h1><p>The report template was not found; see metrics.json.</p>"
           "<p><img src=\"images/reference.png\" alt=\"reference\"></p>";
    for (const auto& m : eq_spp)
      html += "<p>" + std::string(to_string(m.strategy)) + "<br><img src=\"images/" + m.stem + ".png\" alt=\"" +
              to_string(m.strategy) + "\"></p>";
    html += "</body></html>\n";
  }
  std::ofstream(out / "index.html") << html;

  // 12. Summary.
  if (nseeds > 1) std::printf("(relMSE, efficiency and the tail: medians over %d seeds)\n", nseeds);
  std::printf("%-9s %8s %9s %11s %11s %9s %11s %8s\n", "strategy", "spp", "seconds", "relMSE", "efficiency", "vs mis",
              "max rel.e", ">10x px");
  auto print_set = [&](const char* title, const std::vector<Measured>& ms) {
    std::printf("%s\n", title);
    const Measured* mis = nullptr;
    for (const auto& m : ms)
      if (m.strategy == Strategy::Mis) mis = &m;
    for (const auto& m : ms) {
      const double rel = headline_relmse(m);
      const double eff = rel > 0 && m.seconds > 0 ? 1 / (rel * m.seconds) : 0;
      std::printf("%-9s %8d %9.3f %11.4g %11.4g", to_string(m.strategy), m.spp, m.seconds, rel, eff);
      if (mis && rel > 0)
        std::printf(" %8.2fx", headline_relmse(*mis) / rel);
      else
        std::printf(" %9s", "-");
      std::printf(" %11.4g %8g\n", median(over_seeds(m, [](const ImageMetrics& x) { return x.image.max_rel_sq_error; })),
                  median(over_seeds(m, [](const ImageMetrics& x) { return x.image.pixels_over_10x; })));
    }
  };
  print_set("equal spp:", eq_spp);
  if (!eq_time.empty()) print_set("equal time:", eq_time);
  if (!overhead.is_null())
    std::printf("overhead  time(product)/time(mis) = %.3f (wall), %.3f (CPU)\n", overhead["ratio"].get<double>(),
                overhead["ratio_cpu"].is_null() ? 0.0 : overhead["ratio_cpu"].get<double>());
  std::error_code ec;
  const fs::path abs = fs::absolute(out / "index.html", ec);
  std::printf("report    %s\n", (ec ? (out / "index.html") : abs).c_str());
  progress.line("done");
}

const RegisterCommand reg{{"compare",
                           "Compare sampling strategies against a reference: metrics.json, images and an HTML report",
                           [](CLI::App& sub) {
                             auto a = std::make_shared<CompareArgs>();
                             a->common.add_scene_options(sub);
                             sub.add_option("--strategies", a->strategies, "comma-separated strategies to measure")->type_name("LIST")
                                 ->capture_default_str();
                             sub.add_option("--spp", a->spp, "samples per pixel of the equal-spp comparison")->type_name("INT")->capture_default_str();
                             sub.add_option("--ref-spp", a->ref_spp, "samples per pixel of the reference")->type_name("INT")->capture_default_str();
                             sub.add_option("--ref-strategy", a->ref_strategy, "strategy of the reference (rendered with another seed)")
                                 ->type_name("S")->capture_default_str();
                             sub.add_option("--ref-seed", a->ref_seed, "seed of the reference (default: --seed + 1000003)")->type_name("INT");
                             sub.add_option("--equal-time", a->equal_time,
                                            "also compare at equal time: seconds of sampling per strategy, or 'auto' (mis's time at --spp)")
                                 ->type_name("SECONDS|auto");
                             sub.add_option("--width", a->width, "image width (0: from --height and the scene's aspect, or half the scene's)")->type_name("INT")->capture_default_str();
                             sub.add_option("--height", a->height, "image height (0: from --width and the scene's aspect, or half the scene's)")->type_name("INT")->capture_default_str();
                             sub.add_option("--seed", a->seed, "random seed of the measured renders")->type_name("INT")->capture_default_str();
                             sub.add_option("--seeds", a->seeds,
                                            "renders per strategy, seeds --seed, --seed + 1, ...: relMSE and the tail are "
                                            "medians over them, 1..64")
                                 ->type_name("K")
                                 ->capture_default_str();
                             sub.add_option("--repeats", a->repeats, "timing repeats of each equal-spp render under 2 s (minimum kept)")
                                 ->type_name("INT")->capture_default_str();
                             a->common.add_sampling_options(sub);
                             sub.add_option("--cache-dir", a->cache_dir,
                                            "reference cache (default: $ENVPIS_CACHE_DIR or ~/.cache/envpis/references)")->type_name("DIR");
                             sub.add_flag("--no-cache", a->no_cache, "always render the reference; do not cache it");
                             sub.add_flag("--no-convergence", a->no_convergence, "skip the convergence series");
                             sub.add_flag("--no-plots", a->no_plots, "do not run report/plots.py");
                             sub.add_option("--report-dir", a->report_dir, "directory of template.html, report.js, plots.py")->type_name("DIR");
                             sub.add_option("--out", a->out, "output directory (metrics.json, images/, index.html)")->type_name("DIR");
                             sub.add_option("--firefly-log", a->firefly_log,
                                            "write DIR/fireflies-STRATEGY.csv: the samples of each equal-spp render "
                                            "(first seed) whose contribution / spp exceeds --firefly-factor times "
                                            "the reference pixel (docs/fireflies.md)")->type_name("DIR");
                             sub.add_option("--firefly-factor", a->firefly_factor,
                                            "firefly log: F in contribution / spp > F sqrt(R^2 + 0.01) (default 10)")
                                 ->type_name("F");
                             sub.add_flag("--quiet", a->quiet, "no progress lines");
                             sub.callback([a, &sub] {
                               // CLI11 keeps no argv; rebuild the command from what was parsed.
                               std::string cmd = "envpis compare";
                               for (const CLI::Option* o : sub.get_options()) {
                                 if (o->count() == 0 || o->get_name() == "--help") continue;
                                 cmd += " " + o->get_name();
                                 if (o->get_expected_min() > 0)
                                   for (const auto& r : o->results()) cmd += " " + r;
                               }
                               run(*a, cmd);
                             });
                           }}};

}  // namespace
}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
