// SPDX-License-Identifier: Apache-2.0
// Image error metrics of `envpis compare`: an image against the reference, over the whole image and over
// each object's pixels (docs/cli.md, "envpis compare", Method). Every metric derives from one per-pixel
// quantity, the relative squared error e = mean over the three channels of (I - R)^2 / (R^2 + 0.01):
//   relMSE            mean of e over the pixels, with its standard error from the spread of e,
//   max_rel_sq_error  the largest e (the worst pixel: a firefly, or a blotch of bias),
//   pixels_over_10x   how many pixels have e > 100, i.e. are "more than 10x off" (for a grey pixel:
//                     |I - R| > 10 sqrt(R^2 + 0.01), about 10 R for R well above 0.1).
// relMSE alone hides a strategy whose error is a few huge pixels; the last two show that tail.
// Conversely one caustic pixel can decide relMSE; two figures it cannot decide:
//   relmse_trimmed    the mean of e without the set's worst ceil(0.1%) pixels (at least one, never all),
//   median_rel_sq_error  the median of e.
// And how much of the noise environment sampling can act on at all (docs/assets.md):
//   light_variance_share  sum over the pixels of var_light / (R^2 + 0.01) over the same sum of the
//                     pixel's whole variance: the share of the expected relMSE (the variance part of
//                     it) that comes from light samples, var_light being the variance of the part of
//                     the pixel the renderer's light samples brought (RenderResult::light_variance).
//                     Near 0: the error comes from BSDF-sampled paths, no light sampler changes it.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace envpis::app {

/// Offset of the denominator of the relative error, (I - R)^2 / (R^2 + kRelEpsilon): keeps black
/// reference pixels from dominating.
constexpr double kRelEpsilon = 0.01;
/// A pixel is more than 10x off when its relative squared error exceeds 10^2.
constexpr double kTailThreshold = 100;
/// relmse_trimmed leaves out this share of each pixel set's worst pixels (rounded up).
constexpr double kTrimShare = 0.001;

/// The relative squared error of one RGB pixel (three floats) against the reference's.
double pixel_rel_sq_error(const float* rgb, const float* ref_rgb);

/// The metrics of one set of pixels (the image, or one object's pixels). NaN when the set is empty
/// (and `z` when both variances are 0; `relmse_stderr` for a single pixel).
struct PixelSetMetrics {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::size_t pixels = 0;
  double relmse = kNaN;
  double relmse_stderr = kNaN;     // standard error of relmse from the spread of the per-pixel terms
  double mean = kNaN;              // mean over pixels of (R + G + B) / 3
  double z = kNaN;                 // (mean - reference mean) / sqrt(var + reference var)
  double max_rel_sq_error = kNaN;  // the largest per-pixel relative squared error
  std::size_t pixels_over_10x = 0; // pixels whose relative squared error exceeds kTailThreshold
  double relmse_trimmed = kNaN;       // relmse without the worst ceil(kTrimShare n) pixels (n - 1 at most)
  double median_rel_sq_error = kNaN;  // the median per-pixel relative squared error
  double light_variance_share = kNaN; // see above; NaN without the light variance or a noiseless set
};

struct ImageMetrics {
  PixelSetMetrics image;                 // every pixel
  std::vector<PixelSetMetrics> regions;  // one per entry of `region_ids` given to measure()
  std::vector<float> per_pixel;          // each pixel's relative squared error (the error map)
};

/// An RGB image (3 floats per pixel) and its per-pixel variance (of the mean of the channels, the
/// renderer's variance AOV).
struct NoisyImage {
  const std::vector<float>& rgb;
  const std::vector<float>& variance;
  const std::vector<float>* light_variance = nullptr;  // of the light samples' part; null: unknown
};

/// `image` against `reference` (same size); region r is the pixels whose `object_id` is region_ids[r].
ImageMetrics measure(const NoisyImage& image, const NoisyImage& reference, const std::vector<int>& object_id,
                     const std::vector<int>& region_ids);

/// The relMSE the reference's own noise adds to every measurement: the mean over pixels of
/// var(R) / (R^2 + kRelEpsilon), with R the mean of the channels.
double reference_floor(const NoisyImage& reference);

/// The median of `v` (the mean of the two middle values for an even count); NaN for an empty `v`.
double median(std::vector<double> v);

/// The mean of `e` without its largest ceil(kTrimShare n) values (at most n - 1 of them); NaN when empty.
double trimmed_mean(std::vector<double> e);

}  // namespace envpis::app
