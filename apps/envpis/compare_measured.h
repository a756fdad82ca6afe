// SPDX-License-Identifier: Apache-2.0
// What `envpis compare` measures: the objects' pixel sets (regions) and each strategy's renders measured
// against the reference (metrics.h), once per seed.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <string>
#include <vector>

#include "metrics.h"
#include "reference_cache.h"
#include "render/render.h"
#include "render/scene.h"

namespace envpis::app {

/// An object's pixels in the image.
struct Region {
  int id = -1;
  std::string name;
  std::size_t pixels = 0;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // bounding box of the object's pixels, inclusive
  double cx = 0, cy = 0;               // centroid (pixel centres)
};

/// The regions of the scene's objects that cover at least one pixel of the W x H `object_id` AOV.
std::vector<Region> find_regions(const render::Scene& scene, const std::vector<int>& object_id, int W, int H);

/// One strategy at one sample count, over the seeds.
struct Measured {
  render::Strategy strategy;
  int spp = 0;
  double seconds = 0;      // wall, minimum over the runs
  double cpu_seconds = 0;  // process CPU seconds (all threads), minimum over the runs
  std::vector<double> seconds_runs;
  std::size_t nan_count = 0;
  ImageMetrics metrics;                  // of the first seed, whose image is written and shown
  std::vector<ImageMetrics> more_seeds;  // of seeds --seed + 1, ... (--seeds > 1), without per_pixel
  std::string stem;  // images/<stem>.{exr,png}, images/<stem>-error.png
};

/// The strategies measured at one setting (equal spp, or equal time) and their first seed's images.
struct MeasuredSet {
  std::vector<Measured> measured;
  std::vector<render::RenderResult> images;  // one per entry of `measured`
  /// The entry of strategy `s`; null when it was not measured.
  const Measured* find(render::Strategy s) const;
};

/// `r` against the reference, over the image and each region.
ImageMetrics measure_image(const render::RenderResult& r, const Reference& ref, const std::vector<Region>& regions);

/// One number of each seed's metrics, in seed order.
template <class F>
std::vector<double> over_seeds(const Measured& m, F f) {
  std::vector<double> v{double(f(m.metrics))};
  for (const ImageMetrics& x : m.more_seeds) v.push_back(double(f(x)));
  return v;
}

/// The relMSE that compares strategies (and gives the efficiency): the median over the seeds.
double headline_relmse(const Measured& m);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
