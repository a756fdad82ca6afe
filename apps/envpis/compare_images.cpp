// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_images.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "picture.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using namespace envpis::render;

void write_tonemapped_png(const std::string& path, int w, int h, const std::vector<float>& rgb, double k) {
  Image img(w, h);
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const double x = std::isfinite(rgb[i]) ? std::max(0.0f, rgb[i]) : 0.0;
    img.px[i] = static_cast<float>(srgb_encode(1 - std::exp(-k * x)));
  }
  write_png(path, img);
}

void write_error_png(const std::string& path, int w, int h, const std::vector<float>& per_pixel) {
  Image img(w, h);
  for (std::size_t p = 0; p < per_pixel.size(); ++p) {
    const double e = per_pixel[p];
    const double t = e > 0 ? (std::log10(e) - kErrLog10Min) / (kErrLog10Max - kErrLog10Min) : 0.0;
    const Color c = inferno(std::isfinite(t) ? t : 1.0);
    img.px[p * 3] = c.r;
    img.px[p * 3 + 1] = c.g;
    img.px[p * 3 + 2] = c.b;
  }
  write_png(path, img);
}

void write_reference(const fs::path& dir, const CompareSession& session, const Reference& ref, double exposure) {
  RenderResult rr;
  rr.width = session.width;
  rr.height = session.height;
  rr.spp = ref.spp;
  rr.strategy = ref.strategy;
  rr.integrator = session.base.integrator;
  rr.rgb = ref.rgb;
  rr.object_id = ref.object_id;
  write_exr((dir / "reference.exr").string(), rr);
  write_object_id((dir / "object-id.exr").string(), rr);
  write_tonemapped_png((dir / "reference.png").string(), session.width, session.height, ref.rgb, exposure);
}

void write_set(const fs::path& dir, const CompareSession& session, const MeasuredSet& set, double exposure) {
  const int W = session.width, H = session.height;
  for (std::size_t i = 0; i < set.measured.size(); ++i) {
    const Measured& m = set.measured[i];
    write_exr((dir / (m.stem + ".exr")).string(), set.images[i]);
    write_tonemapped_png((dir / (m.stem + ".png")).string(), W, H, set.images[i].rgb, exposure);
    write_error_png((dir / (m.stem + "-error.png")).string(), W, H, m.metrics.per_pixel);
  }
}

}  // namespace

double tonemap_exposure(const Reference& ref) {
  std::vector<float> v;
  const std::size_t npix = static_cast<std::size_t>(ref.width) * ref.height;
  auto grey = [&](std::size_t p) { return (ref.rgb[p * 3] + ref.rgb[p * 3 + 1] + ref.rgb[p * 3 + 2]) / 3; };
  for (std::size_t p = 0; p < npix; ++p)
    if (ref.object_id[p] >= 0) v.push_back(grey(p));
  if (v.empty())
    for (std::size_t p = 0; p < npix; ++p) v.push_back(grey(p));
  if (v.empty()) return 1;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  const double median = v[v.size() / 2];
  return median > 1e-6 ? std::log(2.0) / median : 1.0;
}

void write_images(const CompareSession& session, const Comparison& c, double exposure) {
  const fs::path dir = session.settings.out / "images";
  write_reference(dir, session, c.reference, exposure);
  write_set(dir, session, c.equal_spp, exposure);
  write_set(dir, session, c.equal_time, exposure);
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
