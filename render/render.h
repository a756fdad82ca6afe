// SPDX-License-Identifier: Apache-2.0
// The render API: one call renders a scene with one strategy and returns the image, an object-id AOV
// and timings. Used by `envpis render` and by tools that compare strategies (`envpis compare`).
//
//   Scene scene = make_scene("fig1", env);              // render/scenes.h
//   RenderOptions o;  o.strategy = Strategy::Product;  o.spp = 64;
//   RenderResult r = render(scene, o);                  // r.rgb, r.object_id, r.seconds
//   write_exr("fig1-product.exr", r);
//
// Sampling: Owen-scrambled Sobol points by default, independent numbers on request (render/sampler.h).
// Determinism: pixel (x, y), sample s uses numbers keyed on (sampler, seed, y * width + x, s, dimension)
// only, and each pixel is accumulated by one thread in sample order, so the image is bit-identical at
// any thread count for the same seed.
//
// Pixel filter: a box filter over the pixel (each sample at a uniformly jittered position inside
// the pixel, all samples weighted equally).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "render/firefly_log.h"
#include "render/integrator.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/strategy.h"

namespace envpis::render {

constexpr int kMaxImageSide = 16384;
constexpr std::int64_t kMaxImagePixels = std::int64_t(1) << 26;  // 67 M pixels
constexpr int kMaxSpp = 1 << 24;

struct RenderOptions {
  Strategy strategy = Strategy::Mis;
  IntegratorKind integrator = IntegratorKind::Path;
  Heuristic heuristic = Heuristic::Power;
  SamplerKind sampler = SamplerKind::Sobol;
  int spp = 16;
  std::uint64_t seed = 0;
  int width = 0, height = 0;  ///< 0: the scene camera's default size
  int threads = 0;            ///< 0: all hardware threads (or the enclosing tbb limit)
  int max_depth = 8;          ///< path integrator
  int rr_depth = 3;           ///< path integrator: Russian roulette from this depth on
  /// Cycles' clamp, caustics switches and filter glossy (render/regularization.h); default off.
  RegularizationOptions regularization;
  int tile_size = 16;
  OracleOptions oracle;
  ProductSamplerOptions product;
  /// product: the shared prepared distributions (StrategyTables::product_cache; entries 0: off).
  ProductCacheOptions product_cache;
  int product_depth = 0;  ///< StrategyTables::product_depth
  float product_cache_step = 1.0f / 32.0f;  ///< StrategyTables::product_cache_step
  float product_max_roughness = kInfinity;  ///< StrategyTables::product_max_roughness
  ProductCompensation product_compensation = ProductCompensation::Off;  ///< StrategyTables::product_compensation
  /// The light tables (env, mis, mis-comp, product; see StrategyTables::light_table): top resolution
  /// 1..256 (the paper's 12), fine resolution (0: from the map), the peak bound (0: off).
  ImportanceTableOptions light_table;
  /// Prebuilt tables for this strategy and the scene's environment (e.g. shared between renders);
  /// null: render() builds them (their time is reported in setup_seconds, not seconds).
  const StrategyTables* tables = nullptr;
  /// Firefly log (render/firefly_log.h): null (default) = off, at no cost. When set, every light or
  /// BSDF sample contribution above its threshold is returned in RenderResult::fireflies; the image
  /// is bit-identical either way. Must outlive the call.
  const FireflyLogOptions* firefly_log = nullptr;
  /// Called with the fraction of tiles done (0..1), from worker threads but never concurrently.
  std::function<void(double)> progress;
  /// Sample counts, each in 1..spp - 1, at which each pixel's running estimate is also kept
  /// (RenderResult::prefixes): the image this render would give at that spp, bit for bit, since a
  /// pixel's samples do not depend on spp and are summed in order. Not timed.
  std::vector<int> prefix_spp;
};

/// The image of the first `spp` samples of each pixel (RenderOptions::prefix_spp).
struct PrefixImage {
  int spp = 0;
  std::vector<float> rgb, variance, light_variance;  ///< as RenderResult's
};

struct RenderResult {
  int width = 0, height = 0, spp = 0;
  Strategy strategy = Strategy::Mis;
  IntegratorKind integrator = IntegratorKind::Path;
  std::vector<float> rgb;       ///< width * height * 3, row-major, top row first
  std::vector<float> variance;  ///< per pixel: variance of the pixel's mean of (R+G+B)/3 (sample variance / spp)
  /// per pixel: the same variance of the part light samples brought (Integrator::li's light_part):
  /// how much of the noise environment sampling can act on at all
  std::vector<float> light_variance;
  std::vector<int> object_id;   ///< per pixel: object seen by the ray through the pixel centre, -1 = environment
  double seconds = 0;           ///< wall seconds of the sampling loop
  double cpu_seconds = 0;       ///< process CPU seconds (all threads) of the sampling loop: less
                                ///< sensitive than wall time to other processes sharing the machine
  double setup_seconds = 0;     ///< wall seconds spent building tables (0 when prebuilt)
  /// product with a cache: shading points that reused a prepared distribution, and those that did not
  std::uint64_t product_cache_hits = 0, product_cache_misses = 0;
  std::uint64_t samples = 0;    ///< width * height * spp
  std::size_t nonfinite_pixels = 0;  ///< pixels whose estimate was NaN/Inf: set to 0
  /// With RenderOptions::firefly_log: the contributions above the threshold, sorted (sort_records),
  /// and how many more there were beyond FireflyLogOptions::max_records.
  std::vector<FireflyRecord> fireflies;
  std::size_t fireflies_dropped = 0;
  std::vector<PrefixImage> prefixes;  ///< per RenderOptions::prefix_spp, in its order

  /// prefixes[i] as a render of its own: its image and variances, this render's size and object ids,
  /// no time, fireflies or prefixes (what a render at prefixes[i].spp with the same seed would give).
  RenderResult prefix(std::size_t i) const;

  Rgb pixel(int x, int y) const {
    const float* p = &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
  }
};

/// Throws Error for invalid options (spp, size, threads, depth) or an uncommitted scene.
RenderResult render(const Scene& scene, const RenderOptions& options);
/// The tables a render of `strategy` with `options` samples, as render() builds them when
/// options.tables is null: the options' table settings and the product's vertex rule, and no second
/// table where nothing would sample it (tables_compensation).
StrategyTables build_render_tables(const EnvironmentMap& env, Strategy strategy, const RenderOptions& options);

/// Convenience form for tools that compare strategies: `base` supplies everything else.
inline RenderResult render(const Scene& scene, Strategy strategy, int spp, std::uint64_t seed,
                           RenderOptions base = {}) {
  base.strategy = strategy;
  base.spp = spp;
  base.seed = seed;
  if (base.tables && base.tables->strategy != strategy) base.tables = nullptr;
  return render(scene, base);
}

/// Checks what render() would reject, without rendering (for early command-line validation).
void validate(const RenderOptions& options);

/// Writes the image in the format of path's extension (envpis::write_image_file): a float (32-bit) RGB
/// OpenEXR for .exr, with the strategy, integrator and spp in its header. Throws Error when the file
/// cannot be written.
void write_exr(const std::string& path, const RenderResult& image);
/// Writes the object-id AOV as a one-channel image (channel "id" in an OpenEXR), as write_exr.
void write_object_id(const std::string& path, const RenderResult& image);

/// Mean over the pixels of one object (by the object-id AOV) of (R+G+B)/3, with the variance of
/// that mean from the per-pixel variances (pixels are independent).
struct RegionMean {
  int object = -1;
  std::size_t pixels = 0;
  double mean = 0;
  double variance = 0;
};
std::vector<RegionMean> object_means(const RenderResult& image, int object_count);

}  // namespace envpis::render
