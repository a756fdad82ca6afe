// SPDX-License-Identifier: Apache-2.0
#include "render/render.h"

#include <sys/resource.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <limits>
#include <cmath>
#include <mutex>
#include <optional>

#include "envpis/image_file.h"
#include "render/sampler.h"

namespace envpis::render {

namespace {
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec) + double(u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// The variance of the mean of n samples from their sum and sum of squares (sample variance / n).
double variance_of_mean(double sum, double sum2, double n) {
  const double mean = sum / n;
  return n > 1 ? std::max(0.0, (sum2 - n * mean * mean) / (n - 1)) / n : 0.0;
}

/// Radiance near the 1e30 clamp has a variance beyond float range: saturate it rather than drop a
/// finite pixel.
float saturate_float(double v) { return static_cast<float>(std::min(v, double(std::numeric_limits<float>::max()))); }

/// A pixel's running sums over its samples so far.
struct PixelSums {
  double sum[3] = {0, 0, 0};
  double sum_avg = 0, sum_avg2 = 0, sum_light = 0, sum_light2 = 0;

  /// Writes the estimate of n samples (rgb: 3 floats); false when it is not finite (everything 0 then).
  bool write(double n, float* rgb, float* variance, float* light_variance) const {
    bool finite = true;
    for (int c = 0; c < 3; ++c) {
      rgb[c] = static_cast<float>(sum[c] / n);
      finite = finite && std::isfinite(rgb[c]);
    }
    const double var = variance_of_mean(sum_avg, sum_avg2, n);
    *variance = saturate_float(var);
    *light_variance = saturate_float(variance_of_mean(sum_light, sum_light2, n));
    if (finite && std::isfinite(var)) return true;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    *variance = *light_variance = 0.0f;
    return false;
  }
};
}  // namespace

void validate(const RenderOptions& o) {
  if (o.spp <= 0) throw Error("spp must be positive, got " + std::to_string(o.spp));
  if (o.spp > kMaxSpp) throw Error("spp must be at most " + std::to_string(kMaxSpp));
  if (o.width < 0 || o.height < 0) throw Error("width and height must be positive");
  if (o.width > kMaxImageSide || o.height > kMaxImageSide)
    throw Error("width and height must be at most " + std::to_string(kMaxImageSide));
  if (std::int64_t(o.width) * o.height > kMaxImagePixels) throw Error("image too large");
  if (o.threads < 0) throw Error("threads must be >= 0 (0 = all), got " + std::to_string(o.threads));
  if (o.max_depth < 1) throw Error("max depth must be at least 1, got " + std::to_string(o.max_depth));
  if (o.max_depth > 1024) throw Error("max depth must be at most 1024");
  if (o.rr_depth < 1) throw Error("Russian roulette depth must be at least 1");
  if (o.tile_size < 1 || o.tile_size > 1024) throw Error("tile size must be in 1..1024");
  for (std::size_t i = 0; i < o.prefix_spp.size(); ++i)
    if (o.prefix_spp[i] < 1 || o.prefix_spp[i] >= o.spp || (i > 0 && o.prefix_spp[i] <= o.prefix_spp[i - 1]))
      throw Error("prefix spp must increase and lie in 1.." + std::to_string(o.spp - 1));
  validate(o.regularization);
  const ImportanceTableOptions& lt = o.light_table;
  envpis::validate(lt);
  if (o.tables && o.tables->table &&
      (o.tables->light_table.peak_ratio != lt.peak_ratio || o.tables->light_table.fine_resolution != lt.fine_resolution))
    throw Error("prebuilt tables have other light table options");
  if (o.tables && o.tables->strategy != o.strategy)
    throw Error(std::string("prebuilt tables are for strategy ") + to_string(o.tables->strategy) + ", not " +
                to_string(o.strategy));
  if (o.tables && o.tables->table && o.strategy != Strategy::Oracle &&
      o.tables->light_table.top_resolution != lt.top_resolution)
    throw Error("prebuilt tables have top resolution " + std::to_string(o.tables->light_table.top_resolution) +
                ", not " + std::to_string(lt.top_resolution));
}

StrategyTables build_render_tables(const EnvironmentMap& env, Strategy strategy, const RenderOptions& options) {
  StrategyTables t = StrategyTables::build(
      env, strategy, options.oracle, options.product, options.light_table,
      tables_compensation(options.product_compensation, options.integrator == IntegratorKind::Path,
                          options.product_cache.entries));
  t.product_cache = options.product_cache;
  t.product_depth = options.product_depth;
  t.product_cache_step = options.product_cache_step;
  t.product_max_roughness = options.product_max_roughness;
  return t;
}

RenderResult render(const Scene& scene, const RenderOptions& options) {
  validate(options);
  if (!scene.committed()) throw Error("render: the scene is not committed");
  if (uses_portals(options.strategy) && scene.portals().empty())
    throw Error(std::string("strategy ") + to_string(options.strategy) +
                " needs a scene with portals (a scene file's \"portals\" field)");
  const int W = options.width > 0 ? options.width : scene.camera().width;
  const int H = options.height > 0 ? options.height : scene.camera().height;
  if (W <= 0 || H <= 0 || W > kMaxImageSide || H > kMaxImageSide || std::int64_t(W) * H > kMaxImagePixels)
    throw Error("invalid image size " + std::to_string(W) + "x" + std::to_string(H));
  const Camera camera(scene.camera(), W, H);
  if (options.firefly_log) validate(*options.firefly_log, W, H);

  RenderResult r;
  r.width = W;
  r.height = H;
  r.spp = options.spp;
  r.strategy = options.strategy;
  r.integrator = options.integrator;
  const std::size_t npix = static_cast<std::size_t>(W) * H;
  r.rgb.assign(npix * 3, 0.0f);
  r.variance.assign(npix, 0.0f);
  r.light_variance.assign(npix, 0.0f);
  r.object_id.assign(npix, -1);
  for (int n : options.prefix_spp) {  // validate(): increasing, each in 1..spp - 1
    PrefixImage& im = r.prefixes.emplace_back();
    im.spp = n;
    im.rgb.assign(npix * 3, 0.0f);
    im.variance.assign(npix, 0.0f);
    im.light_variance.assign(npix, 0.0f);
  }
  r.samples = static_cast<std::uint64_t>(npix) * static_cast<std::uint64_t>(options.spp);

  std::optional<StrategyTables> own;
  const StrategyTables* tables = options.tables;
  if (!tables) {
    own = build_render_tables(scene.environment(), options.strategy, options);
    tables = &*own;
    r.setup_seconds = own->build_seconds;
  }

  IntegratorOptions io;
  io.kind = options.integrator;
  io.heuristic = options.heuristic;
  io.max_depth = options.max_depth;
  io.rr_depth = options.rr_depth;
  io.regularization = options.regularization;
  const Integrator integrator(scene, io);

  const int ts = options.tile_size;
  const int tiles_x = (W + ts - 1) / ts, tiles_y = (H + ts - 1) / ts;
  const int tiles = tiles_x * tiles_y;
  std::atomic<int> done{0};
  std::atomic<std::size_t> nonfinite{0};
  std::mutex progress_mutex;
  int last_reported = -1;

  tbb::enumerable_thread_specific<std::optional<LightSampler>> samplers;
  tbb::enumerable_thread_specific<std::optional<FireflyRecorder>> recorders;
  std::atomic<std::size_t> fireflies_kept{0};
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = process_cpu_seconds();
  auto body = [&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(0, tiles, 1),
        [&](const tbb::blocked_range<int>& range) {
          auto& slot = samplers.local();
          if (!slot) slot.emplace(*tables, &scene.portals());
          LightSampler& light = *slot;
          FireflyRecorder* log = nullptr;
          if (options.firefly_log) {
            auto& rec = recorders.local();
            if (!rec) rec.emplace(*options.firefly_log, W, tables->table.get(), &fireflies_kept);
            log = &*rec;
          }
          for (int tile = range.begin(); tile < range.end(); ++tile) {
            const int x0 = (tile % tiles_x) * ts, y0 = (tile / tiles_x) * ts;
            const int x1 = std::min(W, x0 + ts), y1 = std::min(H, y0 + ts);
            for (int y = y0; y < y1; ++y)
              for (int x = x0; x < x1; ++x) {
                const std::size_t pix = static_cast<std::size_t>(y) * W + x;
                PixelSums ps;
                auto& [sum, sum_avg, sum_avg2, sum_light, sum_light2] = ps;
                std::size_t next_prefix = 0;
                const PixelSeeds seeds(options.sampler, options.seed, pix);
                for (int s = 0; s < options.spp; ++s) {
                  PixelSampler rng(seeds, static_cast<std::uint64_t>(s));
                  const Point2 jitter = rng.next2d();
                  const Ray ray = camera.generate_ray(float(x) + jitter.x, float(y) + jitter.y);
                  if (log) log->begin_sample(x, y, s);
                  Rgb light_part;
                  const Rgb L = integrator.li(ray, rng, light, log, &light_part);
                  sum[0] += L.r;
                  sum[1] += L.g;
                  sum[2] += L.b;
                  const double a = (double(L.r) + L.g + L.b) / 3.0;
                  sum_avg += a;
                  sum_avg2 += a * a;
                  const double l = (double(light_part.r) + light_part.g + light_part.b) / 3.0;
                  sum_light += l;
                  sum_light2 += l * l;
                  if (next_prefix < r.prefixes.size() && r.prefixes[next_prefix].spp == s + 1) {
                    PrefixImage& im = r.prefixes[next_prefix++];
                    ps.write(s + 1, &im.rgb[pix * 3], &im.variance[pix], &im.light_variance[pix]);
                  }
                }
                if (!ps.write(options.spp, &r.rgb[pix * 3], &r.variance[pix], &r.light_variance[pix]))
                  nonfinite.fetch_add(1, std::memory_order_relaxed);
                SurfaceHit hit;
                const Ray centre = camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
                r.object_id[pix] = scene.intersect(centre, &hit) ? hit.object : -1;
              }
            const int d = done.fetch_add(1) + 1;
            if (options.progress) {
              std::lock_guard<std::mutex> lock(progress_mutex);
              const int permille = static_cast<int>(1000.0 * d / tiles);
              if (permille > last_reported) {  // threads may finish tiles out of order
                last_reported = permille;
                options.progress(double(d) / tiles);
              }
            }
          }
        },
        tbb::simple_partitioner());
  };
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute(body);
  } else {
    body();
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.cpu_seconds = process_cpu_seconds() - cpu0;
  r.nonfinite_pixels = nonfinite.load();
  for (auto& light : samplers) {
    if (!light) continue;
    r.product_cache_hits += light->product_cache_hits();
    r.product_cache_misses += light->product_cache_misses();
  }
  for (auto& rec : recorders) {
    if (!rec) continue;
    r.fireflies.insert(r.fireflies.end(), rec->records.begin(), rec->records.end());
    r.fireflies_dropped += rec->dropped;
  }
  sort_records(r.fireflies);
  return r;
}

RenderResult RenderResult::prefix(std::size_t i) const {
  const PrefixImage& p = prefixes.at(i);
  RenderResult r;
  r.width = width;
  r.height = height;
  r.spp = p.spp;
  r.strategy = strategy;
  r.integrator = integrator;
  r.rgb = p.rgb;
  r.variance = p.variance;
  r.light_variance = p.light_variance;
  r.object_id = object_id;
  r.samples = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) * static_cast<std::uint64_t>(p.spp);
  return r;
}

void write_exr(const std::string& path, const RenderResult& image) {
  write_image_file(path, image.width, image.height, 3, image.rgb.data(), {"R", "G", "B"},
                   {{"envpis:strategy", to_string(image.strategy)},
                    {"envpis:integrator", to_string(image.integrator)},
                    {"envpis:spp", image.spp}});
}

void write_object_id(const std::string& path, const RenderResult& image) {
  const std::vector<float> ids(image.object_id.begin(), image.object_id.end());
  write_image_file(path, image.width, image.height, 1, ids.data(), {"id"});
}

std::vector<RegionMean> object_means(const RenderResult& image, int object_count) {
  std::vector<RegionMean> m(static_cast<std::size_t>(std::max(0, object_count)));
  for (int i = 0; i < object_count; ++i) m[i].object = i;
  const std::size_t npix = static_cast<std::size_t>(image.width) * image.height;
  for (std::size_t p = 0; p < npix; ++p) {
    const int id = image.object_id[p];
    if (id < 0 || id >= object_count) continue;
    const float* c = &image.rgb[p * 3];
    m[id].pixels += 1;
    m[id].mean += (double(c[0]) + c[1] + c[2]) / 3.0;
    m[id].variance += image.variance[p];
  }
  for (auto& x : m)
    if (x.pixels > 0) {
      x.mean /= double(x.pixels);
      x.variance /= double(x.pixels) * double(x.pixels);
    }
  return m;
}

}  // namespace envpis::render
