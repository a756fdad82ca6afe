// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_measured.h"

#include <algorithm>

namespace envpis::app {

std::vector<Region> find_regions(const render::Scene& scene, const std::vector<int>& object_id, int W, int H) {
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
      const int id = object_id[static_cast<std::size_t>(y) * W + x];
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
  std::vector<Region> regions;
  for (Region& g : all)
    if (g.pixels > 0) {
      g.cx /= double(g.pixels);
      g.cy /= double(g.pixels);
      regions.push_back(g);
    }
  return regions;
}

const Measured* MeasuredSet::find(render::Strategy s) const {
  for (const Measured& m : measured)
    if (m.strategy == s) return &m;
  return nullptr;
}

ImageMetrics measure_image(const render::RenderResult& r, const Reference& ref, const std::vector<Region>& regions) {
  std::vector<int> ids;
  for (const Region& g : regions) ids.push_back(g.id);
  return measure(NoisyImage{r.rgb, r.variance, &r.light_variance}, NoisyImage{ref.rgb, ref.variance}, ref.object_id,
                 ids);
}

double headline_relmse(const Measured& m) {
  return median(over_seeds(m, [](const ImageMetrics& x) { return x.image.relmse; }));
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
