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
#include <OpenImageIO/imageio.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <system_error>
#include <vector>

#include "command.h"
#include "options.h"
#include "envpis/envpis.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// ---------------------------------------------------------------- option parsing (strict, one-line errors)

struct TableArgs {
  std::string env, out;
  std::string layout = "auto";
  std::string rotate = "0", scale = "1";
  std::string orientation = "panorama", filter = "bilinear";
  std::string top = "12", fine = "0", peak_ratio = "8";
  std::string normal = "0,0,1", wo = "1,0,1";
  std::string proxy;  // empty: reflection=1, alpha_r=0.2
  std::string transform, min_alpha, max_alpha, env_mix = "0";
  std::string samples = "1000", seed = "1";
};

Vec3 parse_vec3(const std::string& option, const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (parts.size() != 3)
    throw Error(option + ": expected three comma-separated numbers x,y,z, got '" + text + "'");
  float c[3];
  for (int i = 0; i < 3; ++i) {
    double v = 0;
    try {
      v = parse_number(option, parts[i]);
    } catch (const Error&) {
      throw Error(option + ": expected three comma-separated finite numbers x,y,z, got '" + text + "'");
    }
    if (std::fabs(v) > 1e30) throw Error(option + ": component out of range in '" + text + "'");
    c[i] = static_cast<float>(v);
  }
  const Vec3 v{c[0], c[1], c[2]};
  if (!is_valid_direction(v)) throw Error(option + ": the vector must be non-zero, got '" + text + "'");
  return normalize(v);
}

// --proxy key=value,... : unmentioned weights are 0, roughnesses 0.2, ior 1.5.
BsdfProxy parse_proxy(const std::string& text) {
  BsdfProxy p;
  p.alpha_reflection = p.alpha_refraction = 0.2f;
  p.ior = 1.5f;
  if (text.empty()) {
    p.reflection = 1.0f;
    return p;
  }
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos)
      throw Error("--proxy: expected key=value, got '" + item + "' (keys: diffuse, translucent, reflection, "
                  "refraction, alpha_r, alpha_t, ior)");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    const std::string opt = "--proxy " + key;
    if (key == "diffuse") {
      p.diffuse = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "translucent") {
      p.translucent = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "reflection") {
      p.reflection = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "refraction") {
      p.refraction = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "alpha_r") {
      p.alpha_reflection = float(parse_number_in(opt, value, 0, 1, "in [0, 1]"));
    } else if (key == "alpha_t") {
      p.alpha_refraction = float(parse_number_in(opt, value, 0, 1, "in [0, 1]"));
    } else if (key == "ior") {
      p.ior = float(parse_number_in(opt, value, 1e-3, 1e3, "in [0.001, 1000]"));
    } else {
      throw Error("--proxy: unknown key '" + key +
                  "' (keys: diffuse, translucent, reflection, refraction, alpha_r, alpha_t, ior)");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return p;
}

// Creates DIR (and parents) and checks that a file can be written in it.
void prepare_output_dir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create output directory '" + dir + "': " + ec.message());
  if (!fs::is_directory(dir, ec)) throw Error("output path '" + dir + "' exists and is not a directory");
  const fs::path probe = fs::path(dir) / ".envpis-write-test";
  {
    std::ofstream f(probe);
    if (!f || !(f << "x") || !(f.flush()))
      throw Error("cannot write to output directory '" + dir + "': " + std::strerror(errno));
  }
  fs::remove(probe, ec);
}

// ---------------------------------------------------------------- pictures

struct Color {
  float r = 0, g = 0, b = 0;
};

struct Image {
  int w = 0, h = 0;
  std::vector<float> px;  // display-referred RGB in [0,1], row-major, top row first
  Image(int w_, int h_, Color c = {}) : w(w_), h(h_), px(std::size_t(w_) * h_ * 3) {
    for (std::size_t i = 0; i < px.size(); i += 3) {
      px[i] = c.r;
      px[i + 1] = c.g;
      px[i + 2] = c.b;
    }
  }
  void blend(int x, int y, Color c, float a = 1.0f) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    float* p = &px[(std::size_t(y) * w + x) * 3];
    p[0] += (c.r - p[0]) * a;
    p[1] += (c.g - p[1]) * a;
    p[2] += (c.b - p[2]) * a;
  }
  void disc(float cx, float cy, float r, Color c) {
    for (int y = int(std::floor(cy - r)); y <= int(std::ceil(cy + r)); ++y)
      for (int x = int(std::floor(cx - r)); x <= int(std::ceil(cx + r)); ++x) {
        const float dx = x + 0.5f - cx, dy = y + 0.5f - cy;
        if (dx * dx + dy * dy <= r * r) blend(x, y, c);
      }
  }
  void ring(float cx, float cy, float r, float thickness, Color c) {
    const float ro = r + thickness;
    for (int y = int(std::floor(cy - ro)); y <= int(std::ceil(cy + ro)); ++y)
      for (int x = int(std::floor(cx - ro)); x <= int(std::ceil(cx + ro)); ++x) {
        const float d = std::hypot(x + 0.5f - cx, y + 0.5f - cy);
        if (d >= r && d <= ro) blend(x, y, c);
      }
  }
  void plus(float cx, float cy, int arm, int thickness, Color c) {
    for (int t = -thickness / 2; t <= thickness / 2; ++t)
      for (int i = -arm; i <= arm; ++i) {
        blend(int(cx) + i, int(cy) + t, c);
        blend(int(cx) + t, int(cy) + i, c);
      }
  }
  // Line from (x0,y0) to (x1,y1); dash > 0 draws dashes of that many pixels.
  void line(float x0, float y0, float x1, float y1, Color c, float a, int dash = 0) {
    const int steps = std::max(1, int(std::ceil(std::max(std::fabs(x1 - x0), std::fabs(y1 - y0)))));
    for (int i = 0; i <= steps; ++i) {
      if (dash > 0 && (i / dash) % 2 == 1) continue;
      const float t = float(i) / steps;
      blend(int(x0 + (x1 - x0) * t), int(y0 + (y1 - y0) * t), c, a);
    }
  }
};

// A few samples of matplotlib's "inferno" colormap, linearly interpolated (t in [0,1]).
Color inferno(float t) {
  static const float k[11][3] = {{0, 0, 4},       {22, 11, 57},   {66, 10, 104},  {106, 23, 110},
                                 {147, 38, 103},  {188, 55, 84},  {221, 81, 58},  {243, 120, 25},
                                 {252, 165, 10},  {246, 215, 70}, {252, 255, 164}};
  t = std::clamp(t, 0.0f, 1.0f) * 10.0f;
  const int i = std::min(int(t), 9);
  const float f = t - i;
  return {(k[i][0] + (k[i + 1][0] - k[i][0]) * f) / 255.0f, (k[i][1] + (k[i + 1][1] - k[i][1]) * f) / 255.0f,
          (k[i][2] + (k[i + 1][2] - k[i][2]) * f) / 255.0f};
}

float srgb_encode(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

void write_png(const fs::path& path, const Image& img) {
  const std::string name = path.string();
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw Error("cannot write '" + name + "': " + OIIO::geterror());
  const OIIO::ImageSpec spec(img.w, img.h, 3, OIIO::TypeDesc::UINT8);
  if (!out->open(name, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, img.px.data()) || !out->close())
    throw Error("cannot write '" + name + "': " + out->geterror());
}

// The map in its own layout: exposure so that the log-average luminance lands at 0.18, Reinhard, sRGB.
Image tonemap_map(const EnvironmentMap& map) {
  const int w = map.width(), h = map.height();
  double log_sum = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb c = map.texel(x, y);
      log_sum += std::log(1e-4 + 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b);
    }
  const double log_avg = std::exp(log_sum / (double(w) * h));
  const float exposure = static_cast<float>(0.18 / std::max(log_avg, 1e-6));
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Rgb c = map.texel(x, y) * exposure;
      const float lum = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
      const float k = lum > 0 ? 1.0f / (1.0f + lum) : 1.0f;
      img.blend(x, y, {srgb_encode(c.r * k), srgb_encode(c.g * k), srgb_encode(c.b * k)});
    }
  return img;
}

// Log-scaled fine importance, t in [0,1] per fine texel: from the 0.5th percentile (at most six
// decades below the top) to the 99.9th percentile (so the sky is not crushed by a tiny sun, which
// saturates to the colormap's white end).
std::vector<float> importance_levels(const ImportanceTable& table) {
  const int n = table.fine_resolution();
  std::vector<float> v(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) v[std::size_t(y) * n + x] = table.importance(x, y);
  std::vector<float> sorted = v;
  const std::size_t k = sorted.size() / 200, kh = sorted.size() - 1 - sorted.size() / 1000;
  std::nth_element(sorted.begin(), sorted.begin() + kh, sorted.end());
  const float hi = sorted[kh] > 0 ? sorted[kh] : *std::max_element(v.begin(), v.end());
  std::nth_element(sorted.begin(), sorted.begin() + k, sorted.begin() + kh);
  float lo = std::max(sorted[k], hi * 1e-6f);
  if (!(hi > 0)) return std::vector<float>(v.size(), 0.0f);
  if (!(lo < hi)) lo = hi * 0.1f;
  const float l0 = std::log(lo), inv = 1.0f / (std::log(hi) - l0);
  for (float& x : v) x = x > 0 ? std::clamp((std::log(x) - l0) * inv, 0.0f, 1.0f) : 0.0f;
  return v;
}

// Horizon diamond, top-level grid, normal and lobe axes drawn on a square picture of side s.
void draw_overlays(Image& img, int T, const PreparedProxy* proxy, Vec3 normal, bool grid, float grid_alpha) {
  const float s = float(img.w);
  if (grid)
    for (int i = 0; i <= T; ++i) {
      const float p = std::min(s - 1, std::floor(i * s / T));
      img.line(p, 0, p, s - 1, {0.55f, 0.55f, 0.55f}, grid_alpha);
      img.line(0, p, s - 1, p, {0.55f, 0.55f, 0.55f}, grid_alpha);
    }
  const Color white{1, 1, 1};
  const float h = s * 0.5f, e = s - 1;
  img.line(h, 0, e, h, white, 0.6f, 6);
  img.line(e, h, h, e, white, 0.6f, 6);
  img.line(h, e, 0, h, white, 0.6f, 6);
  img.line(0, h, h, 0, white, 0.6f, 6);
  const float r = std::max(5.0f, s * 0.018f), th = std::max(2.0f, s * 0.004f);
  auto at = [&](Vec3 d) {
    const Point2 p = equal_area_sphere_to_square(d);
    return Point2{p.x * s, p.y * s};
  };
  const Point2 pn = at(normal);
  img.plus(pn.x, pn.y, int(r), int(th), {0.2f, 1.0f, 0.2f});
  if (!proxy || !proxy->valid()) return;
  if (proxy->kd > 0) {
    const Point2 p = at(proxy->n);
    img.ring(p.x, p.y, r, th, {0.2f, 1.0f, 0.2f});
  }
  if (proxy->kt > 0) {
    const Point2 p = at(-proxy->n);
    img.ring(p.x, p.y, r, th, {0.2f, 1.0f, 0.2f});
  }
  if (proxy->wr > 0) {
    const Point2 p = at(proxy->r);
    img.ring(p.x, p.y, r * 1.4f, th, {0.1f, 0.9f, 1.0f});
  }
  if (proxy->wt > 0) {
    const Point2 p = at(proxy->t);
    img.ring(p.x, p.y, r * 1.8f, th, {1.0f, 0.2f, 1.0f});
  }
}

// T x T probabilities, log scale over four decades below the largest (zero cells dark grey).
Image cell_image(int T, const std::vector<float>& prob) {
  const int c = std::max(3, 768 / T), s = c * T;
  const float pmax = *std::max_element(prob.begin(), prob.end());
  Image img(s, s);
  for (int cy = 0; cy < T; ++cy)
    for (int cx = 0; cx < T; ++cx) {
      const float p = prob[std::size_t(cy) * T + cx];
      const Color col = p > 0 && pmax > 0 ? inferno(0.06f + 0.94f * std::max(0.0f, 1.0f + std::log10(p / pmax) / 4))
                                          : Color{0.16f, 0.16f, 0.16f};
      for (int y = cy * c; y < (cy + 1) * c; ++y)
        for (int x = cx * c; x < (cx + 1) * c; ++x) img.blend(x, y, col);
    }
  return img;
}

Json vec_json(Vec3 v) { return Json::array({v.x, v.y, v.z}); }

std::string mib(std::size_t bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f MiB", double(bytes) / (1024.0 * 1024.0));
  return buf;
}

// ---------------------------------------------------------------- the command

void run_table(const TableArgs& a) {
  // 1. Validate everything cheap before touching the file system.
  if (a.env.empty()) throw Error("--env FILE is required");
  if (a.out.empty()) throw Error("--out DIR is required");
  EnvironmentMapOptions map_options;
  map_options.layout = with_option("--layout", [&] { return parse_map_layout(a.layout); });
  const float rotate = float(parse_number_in("--rotate", a.rotate, -1e6, 1e6, "in [-1e6, 1e6] degrees"));
  map_options.rotation = Mat3::rotate_z(rotate);
  map_options.scale = float(parse_number_in("--scale", a.scale, 0, 1e30, ">= 0"));
  map_options.orientation = with_option("--env-orientation", [&] { return parse_latlong_orientation(a.orientation); });
  map_options.filter = with_option("--env-filter", [&] { return parse_map_filter(a.filter); });
  ImportanceTableOptions table_options;
  table_options.top_resolution = int(parse_integer("--top", a.top, 1, 256));
  table_options.fine_resolution = int(parse_integer("--fine", a.fine, 0, 16384));
  table_options.peak_ratio = parse_peak_ratio(a.peak_ratio);
  const Vec3 normal = parse_vec3("--normal", a.normal);
  const Vec3 wo = parse_vec3("--wo", a.wo);
  const BsdfProxy proxy = parse_proxy(a.proxy);
  ProductSamplerOptions sampler_options;
  if (!a.transform.empty())
    sampler_options.proxy.transform = with_option("--transform", [&] { return parse_roughness_transform(a.transform); });
  if (!a.min_alpha.empty())
    sampler_options.proxy.min_alpha = float(parse_number_in("--min-alpha", a.min_alpha, 0, 1, "in [0, 1]"));
  if (!a.max_alpha.empty())
    sampler_options.proxy.max_alpha = float(parse_number_in("--max-alpha", a.max_alpha, 0, 1, "in [0, 1]"));
  sampler_options.env_mix = float(parse_number_in("--env-mix", a.env_mix, 0, 1, "in [0, 1]"));
  const long long samples = parse_integer("--samples", a.samples, 1, 10000000);
  const unsigned long long seed = static_cast<unsigned long long>(parse_integer("--seed", a.seed, 0, 1LL << 62));
  const fs::path out(a.out);
  prepare_output_dir(a.out);

  // 2. The map.
  const EnvironmentMap map = [&] {
    try {
      return EnvironmentMap::load(a.env, map_options);
    } catch (const Error& e) {  // the loader's messages name the file; the layout check does not
      if (std::string(e.what()).find(a.env) != std::string::npos) throw;
      throw Error("cannot use environment map '" + a.env + "': " + e.what());
    }
  }();
  if (map.is_black())
    throw Error("environment map '" + a.env +
                "' has no positive radiance (black everywhere after repair and --scale): the importance "
                "table would be empty, there is nothing to sample");
  std::printf("map:     %s  %dx%d %s  scale %g  rotate %g deg  orientation %s  filter %s\n", a.env.c_str(),
              map.width(), map.height(), to_string(map.layout()), double(map.scale()), double(rotate),
              map.layout() == MapLayout::LatLong ? to_string(map.orientation()) : "n/a", to_string(map.filter()));
  for (const std::string& w : map.warnings()) std::fprintf(stderr, "envpis table: warning: %s\n", w.c_str());
  write_png(out / "map.png", tonemap_map(map));

  // 3. The table.
  const ImportanceTable table(map, table_options);
  const int T = table.top_resolution(), F = table.cell_resolution(), N = table.fine_resolution();
  const int threads = tbb::this_task_arena::max_concurrency();
  std::printf("table:   T=%d (%d top cells)  F=%d  N=%d (%lld fine texels)\n", T, T * T, F, N,
              static_cast<long long>(N) * N);
  std::printf("build:   %.4f s (%d threads)\n", table.build_seconds(), threads);
  const std::size_t bytes = table.bytes_used(), single = table.single_level_bytes();
  std::printf("memory:  table %zu bytes (%s); single-level 2D CDF over the same texels %zu bytes (%s); "
              "ratio %.4f\n",
              bytes, mib(bytes).c_str(), single, mib(single).c_str(), double(bytes) / double(single));
  if (table.empty())
    throw Error("environment map '" + a.env +
                "' has no positive radiance (black everywhere after repair and --scale): the importance "
                "table is empty, there is nothing to sample");

  // 4. The product for the shading point.
  ProductSampler sampler(table, sampler_options);
  if (!sampler.prepare(normal, wo, proxy)) throw Error("the product sampler rejected the shading point");
  const auto t0 = std::chrono::steady_clock::now();
  const int reps = 2000;
  for (int i = 0; i < reps; ++i) sampler.prepare(normal, wo, proxy);
  const double prepare_ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / reps;
  const PreparedProxy& pp = sampler.prepared_proxy();
  std::printf("shading: normal (%.4g, %.4g, %.4g)  wo (%.4g, %.4g, %.4g)\n", normal.x, normal.y, normal.z, wo.x,
              wo.y, wo.z);
  std::printf("proxy:   diffuse=%g translucent=%g reflection=%g refraction=%g alpha_r=%g alpha_t=%g ior=%g\n",
              double(proxy.diffuse), double(proxy.translucent), double(proxy.reflection), double(proxy.refraction),
              double(proxy.alpha_reflection), double(proxy.alpha_refraction), double(proxy.ior));
  std::printf("         transform %s, min-alpha %g, max-alpha %g -> alpha_r' %.4g alpha_t' %.4g eta %.4g%s\n",
              to_string(sampler_options.proxy.transform), double(sampler_options.proxy.min_alpha),
              double(sampler_options.proxy.max_alpha),
              double(pp.alpha_r), double(pp.alpha_t), double(pp.eta), pp.tir ? " (total internal reflection)" : "");
  if (sampler.uses_environment_fallback())
    std::fprintf(stderr,
                 "envpis table: warning: the proxy gives no cell a positive weight (all-zero proxy?): the "
                 "product sampler falls back to environment-only sampling\n");
  std::printf("product: prepare %.0f ns per shading point (%s)\n", prepare_ns, to_string(sampler.simd()));

  std::vector<float> env_prob(std::size_t(T) * T), prod_prob(std::size_t(T) * T);
  for (int c = 0; c < T * T; ++c) {
    env_prob[c] = table.cell_probability(c);
    prod_prob[c] = sampler.cell_probability(c);
  }

  // 5. Samples.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::vector<Point2> points;
  points.reserve(std::size_t(samples));
  std::vector<long long> per_cell(std::size_t(T) * T, 0);
  long long above = 0, rejected = 0;
  double max_rel = 0;
  for (long long i = 0; i < samples; ++i) {
    Point2 u{uni(rng), uni(rng)};
    u.x = std::min(u.x, 0.99999994f);
    u.y = std::min(u.y, 0.99999994f);
    const DirectionSample s = sampler.sample(u);
    if (!(s.pdf > 0)) {
      ++rejected;
      continue;
    }
    const float p = sampler.pdf(s.direction);
    max_rel = std::max(max_rel, std::fabs(double(p) - s.pdf) / s.pdf);
    points.push_back(equal_area_sphere_to_square(s.direction));
    ++per_cell[std::size_t(table.cell_of_direction(s.direction))];
    if (dot(s.direction, normal) > 0) ++above;
  }
  // Share of the samples in the 5 most probable cells versus their probability.
  std::vector<int> order(std::size_t(T) * T);
  for (int c = 0; c < T * T; ++c) order[c] = c;
  const int top_k = std::min(5, T * T);
  std::partial_sort(order.begin(), order.begin() + top_k, order.end(),
                    [&](int x, int y) { return prod_prob[x] > prod_prob[y]; });
  double expected_top = 0, observed_top = 0;
  for (int i = 0; i < top_k; ++i) {
    expected_top += prod_prob[order[i]];
    observed_top += double(per_cell[order[i]]) / double(samples);
  }
  std::printf("samples: %lld (seed %llu): %.1f%% above the surface; %d most probable cells hold %.1f%% "
              "(expected %.1f%%); max |pdf(dir) - sample pdf| / pdf = %.2g%s\n",
              samples, seed, 100.0 * above / double(samples), top_k, 100.0 * observed_top, 100.0 * expected_top,
              max_rel, rejected ? " (some samples had pdf 0!)" : "");

  // 6. Pictures.
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
  write_png(out / "importance.png", importance);
  write_png(out / "top_level.png", top);
  write_png(out / "product_weights.png", weights);
  write_png(out / "product_samples.png", dots);

  // 7. summary.json.
  Json j;
  j["version"] = kVersion;
  const MapLoadReport& rep = map.load_report();
  j["map"] = {{"path", a.env},
              {"format", rep.format},
              {"width", map.width()},
              {"height", map.height()},
              {"layout", to_string(map.layout())},
              {"scale", map.scale()},
              {"rotate_degrees", rotate},
              {"orientation", map.layout() == MapLayout::LatLong ? to_string(map.orientation()) : "n/a"},
              {"filter", to_string(map.filter())},
              {"repaired", {{"nan", rep.nan_texels}, {"inf", rep.inf_texels}, {"negative", rep.negative_texels}}}};
  j["table"] = {{"top_resolution", T},
                {"cell_resolution", F},
                {"fine_resolution", N},
                {"build_seconds", table.build_seconds()},
                {"threads", threads},
                {"bytes_used", bytes},
                {"single_level_bytes", single},
                {"memory_ratio", double(bytes) / double(single)},
                {"integral", table.integral()},
                {"peak_ratio", table_options.peak_ratio}};
  j["shading_point"] = {
      {"normal", vec_json(normal)},
      {"wo", vec_json(wo)},
      {"proxy",
       {{"diffuse", proxy.diffuse},
        {"translucent", proxy.translucent},
        {"reflection", proxy.reflection},
        {"refraction", proxy.refraction},
        {"alpha_r", proxy.alpha_reflection},
        {"alpha_t", proxy.alpha_refraction},
        {"ior", proxy.ior}}},
      {"transform", to_string(sampler_options.proxy.transform)},
      {"min_alpha", sampler_options.proxy.min_alpha},
      {"max_alpha", sampler_options.proxy.max_alpha},
      {"env_mix", sampler_options.env_mix},
      {"prepared",
       {{"alpha_r", pp.alpha_r}, {"alpha_t", pp.alpha_t}, {"eta", pp.eta}, {"tir", pp.tir},
        {"reflection_axis", vec_json(pp.r)}, {"refraction_axis", vec_json(pp.t)}}},
      {"environment_fallback", sampler.uses_environment_fallback()},
      {"prepare_ns", prepare_ns},
      {"simd", to_string(sampler.simd())}};
  j["samples"] = {{"count", samples},
                  {"seed", seed},
                  {"above_surface", double(above) / double(samples)},
                  {"top_cells", top_k},
                  {"top_cells_observed", observed_top},
                  {"top_cells_expected", expected_top},
                  {"max_pdf_relative_error", max_rel},
                  {"zero_pdf", rejected}};
  j["cells"] = {{"environment_probability", env_prob}, {"product_probability", prod_prob}, {"samples", per_cell}};
  j["outputs"] = {"map.png", "importance.png", "top_level.png", "product_weights.png", "product_samples.png"};
  const fs::path json_path = out / "summary.json";
  std::ofstream f(json_path);
  if (!f || !(f << j.dump(2) << '\n') || !f.flush()) throw Error("cannot write '" + json_path.string() + "'");
  std::printf("wrote:   %s/{map,importance,top_level,product_weights,product_samples}.png, summary.json\n",
              out.string().c_str());
}

const RegisterCommand kTable{Command{
    "table", "Build an environment map's importance table, print its figures and write pictures of it",
    [](CLI::App& sub) {
      auto a = std::make_shared<TableArgs>();
      sub.add_option("--env", a->env, "Environment map (OpenEXR, Radiance HDR, ...) (required)")->type_name("FILE");
      sub.add_option("--out", a->out, "Output directory, created if needed (required)")->type_name("DIR");
      sub.add_option("--layout", a->layout, "Map layout: auto, latlong or equal-area (default auto)")
          ->type_name("L");
      sub.add_option("--rotate", a->rotate, "Rotate the map about +Z (up) by DEG degrees (default 0)")
          ->type_name("DEG");
      sub.add_option("--scale", a->scale, "Multiply the map's radiance by S >= 0 (default 1)")->type_name("S");
      sub.add_option("--env-orientation", a->orientation,
                     "Lat-long column direction: panorama (Blender/Cycles: +X at the centre column) or legacy "
                     "(+X at the left edge, mirrored) (default panorama)")
          ->type_name("O");
      sub.add_option("--env-filter", a->filter, "Radiance look-up: bilinear or nearest (default bilinear)")
          ->type_name("F");
      sub.add_option("--top", a->top, "Top-level resolution T, 1..256 (default 12)")->type_name("T");
      sub.add_option("--fine", a->fine, "Fine resolution N (rounded up to a multiple of T); 0 = from the map's "
                                        "texel count (default)")
          ->type_name("N");
      sub.add_option("--peak-ratio", a->peak_ratio,
                     "Each texel's importance is at least 1/K of the radiance the look-up reaches in it; 0 = off "
                     "(default 8)")
          ->type_name("K");
      sub.add_option("--normal", a->normal, "Shading normal (default 0,0,1)")->type_name("x,y,z");
      sub.add_option("--wo", a->wo, "Outgoing direction, towards the viewer (default 1,0,1 normalized)")
          ->type_name("x,y,z");
      sub.add_option("--proxy", a->proxy,
                     "BSDF proxy: diffuse=,translucent=,reflection=,refraction= weights, alpha_r=,alpha_t= GGX "
                     "roughness, ior= (unmentioned weights 0, roughness 0.2, ior 1.5; default reflection=1)")
          ->type_name("k=v,...");
      sub.add_option("--transform", a->transform, "Proxy roughness transform: slides, abstract or hybrid (default: the "
                                                  "library's)")
          ->type_name("NAME");
      sub.add_option("--min-alpha", a->min_alpha, "Floor on the transformed roughness, [0,1] (default: the "
                                                  "library's)")
          ->type_name("A");
      sub.add_option("--max-alpha", a->max_alpha, "Cap on the transformed roughness, [0,1] (default: the "
                                                  "library's)")
          ->type_name("A");
      sub.add_option("--env-mix", a->env_mix, "Fraction of environment-only sampling mixed in, [0,1] (default 0)")
          ->type_name("M");
      sub.add_option("--samples", a->samples, "Product samples drawn on product_samples.png (default 1000)")
          ->type_name("K");
      sub.add_option("--seed", a->seed, "Random seed (default 1)")->type_name("K");
      sub.callback([a] { run_table(*a); });
    }}};

}  // namespace
}  // namespace envpis::app
