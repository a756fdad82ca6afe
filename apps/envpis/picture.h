// SPDX-License-Identifier: Apache-2.0
// Pictures the envpis commands write for a person to look at: a display-referred RGB image with a few
// drawing primitives, the inferno colour map, the sRGB encoding and 8-bit PNG writing. `envpis table`
// draws its importance pictures with them, `envpis compare` its tonemapped images and error maps.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace envpis::app {

/// A display-referred colour, each channel in [0, 1].
struct Color {
  float r = 0, g = 0, b = 0;
};

/// W x H display-referred RGB (3 floats per pixel, row-major, top row first). Drawing outside the
/// image is ignored.
struct Image {
  int w = 0, h = 0;
  std::vector<float> px;

  Image(int width, int height, Color fill = {});
  /// Mixes `c` into pixel (x, y) with opacity `a`.
  void blend(int x, int y, Color c, float a = 1.0f);
  void disc(float cx, float cy, float r, Color c);
  void ring(float cx, float cy, float r, float thickness, Color c);
  void plus(float cx, float cy, int arm, int thickness, Color c);
  /// Line from (x0, y0) to (x1, y1) with opacity `a`; dash > 0 draws dashes of that many pixels.
  void line(float x0, float y0, float x1, float y1, Color c, float a, int dash = 0);
};

/// matplotlib's "inferno" at 9 evenly spaced stops, 0..255 per channel. compare's metrics.json carries
/// them so the report's legend shows the colours of the error maps.
const std::vector<std::array<int, 3>>& inferno_stops();
/// inferno at t in [0, 1] (clamped), linear between the stops.
Color inferno(double t);

/// The sRGB transfer function of a linear value, clamped to [0, 1].
double srgb_encode(double linear);

/// Writes `img` as an 8-bit RGB PNG (each channel rounded to the nearest of 0..255); throws Error
/// naming the file when it cannot be written.
void write_png(const std::string& path, const Image& img);

}  // namespace envpis::app
