// SPDX-License-Identifier: Apache-2.0
#include "metrics.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace envpis::app {

double pixel_rel_sq_error(const float* rgb, const float* ref_rgb) {
  double e = 0;
  for (int c = 0; c < 3; ++c) {
    const double I = rgb[c], R = ref_rgb[c];
    e += (I - R) * (I - R) / (R * R + kRelEpsilon);
  }
  return e / 3;
}

namespace {

/// Running sums over one set of pixels, and its per-pixel errors (for the trimmed mean and the median).
struct Sums {
  std::size_t n = 0, over = 0;
  double e = 0, e2 = 0, max_e = 0;
  double value = 0, variance = 0, ref_value = 0, ref_variance = 0;
  double rel_variance = 0, rel_light_variance = 0;  // sums of var / (R^2 + eps), whole and light part
  std::vector<double> errors;

  void add(double err, double v, double var, double ref_v, double ref_var) {
    ++n;
    errors.push_back(err);
    e += err;
    e2 += err * err;
    max_e = std::max(max_e, err);
    if (err > kTailThreshold) ++over;
    value += v;
    variance += var;
    ref_value += ref_v;
    ref_variance += ref_var;
  }

  PixelSetMetrics finish() const {
    PixelSetMetrics m;
    m.pixels = n;
    if (n == 0) return m;
    const double N = double(n);
    m.relmse = e / N;
    // Standard error of a mean of n independent per-pixel terms: sqrt(sample variance / n).
    if (n > 1) m.relmse_stderr = std::sqrt(std::max(0.0, (e2 - e * e / N) / (N - 1)) / N);
    m.mean = value / N;
    const double var = (variance + ref_variance) / (N * N);
    if (var > 0) m.z = (value - ref_value) / N / std::sqrt(var);
    m.max_rel_sq_error = max_e;
    m.pixels_over_10x = over;
    m.relmse_trimmed = trimmed_mean(errors);
    m.median_rel_sq_error = median(errors);
    if (rel_variance > 0) m.light_variance_share = rel_light_variance / rel_variance;
    return m;
  }
};

double channel_mean(const std::vector<float>& rgb, std::size_t p) {
  return (double(rgb[p * 3]) + rgb[p * 3 + 1] + rgb[p * 3 + 2]) / 3;
}

}  // namespace

ImageMetrics measure(const NoisyImage& image, const NoisyImage& reference, const std::vector<int>& object_id,
                     const std::vector<int>& region_ids) {
  const std::size_t npix = reference.variance.size();
  std::map<int, std::size_t> region_of_id;
  for (std::size_t r = 0; r < region_ids.size(); ++r) region_of_id[region_ids[r]] = r;
  Sums all;
  std::vector<Sums> regions(region_ids.size());
  ImageMetrics m;
  m.per_pixel.resize(npix);
  const bool light = image.light_variance && image.light_variance->size() == npix;
  for (std::size_t p = 0; p < npix; ++p) {
    const double e = pixel_rel_sq_error(&image.rgb[p * 3], &reference.rgb[p * 3]);
    m.per_pixel[p] = static_cast<float>(e);
    const double v = channel_mean(image.rgb, p), r = channel_mean(reference.rgb, p);
    Sums* region = nullptr;
    if (p < object_id.size())
      if (auto it = region_of_id.find(object_id[p]); it != region_of_id.end()) region = &regions[it->second];
    for (Sums* s : {&all, region}) {
      if (!s) continue;
      s->add(e, v, image.variance[p], r, reference.variance[p]);
      if (!light) continue;
      const double scale = 1 / (r * r + kRelEpsilon);  // the relMSE's weight of the pixel's variance
      s->rel_variance += image.variance[p] * scale;
      s->rel_light_variance += (*image.light_variance)[p] * scale;
    }
  }
  m.image = all.finish();
  for (const Sums& s : regions) m.regions.push_back(s.finish());
  return m;
}

double reference_floor(const NoisyImage& reference) {
  const std::size_t npix = reference.variance.size();
  double total = 0;
  for (std::size_t p = 0; p < npix; ++p) {
    const double R = channel_mean(reference.rgb, p);
    total += reference.variance[p] / (R * R + kRelEpsilon);
  }
  return npix ? total / double(npix) : std::nan("");
}

double trimmed_mean(std::vector<double> e) {
  if (e.empty()) return std::nan("");
  const auto k = std::min(e.size() - 1, static_cast<std::size_t>(std::ceil(kTrimShare * double(e.size()))));
  const std::size_t keep = e.size() - k;
  std::nth_element(e.begin(), e.begin() + (keep - 1), e.end());  // the `keep` smallest come first
  double sum = 0;
  for (std::size_t i = 0; i < keep; ++i) sum += e[i];
  return sum / double(keep);
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  const std::size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + h, v.end());
  if (v.size() % 2) return v[h];
  return (*std::max_element(v.begin(), v.begin() + h) + v[h]) / 2;
}

}  // namespace envpis::app
