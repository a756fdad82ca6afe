// SPDX-License-Identifier: Apache-2.0
#include "picture.h"

#include "envpis/image_file.h"

#include <algorithm>
#include <cmath>

#include "envpis/envpis.h"

namespace envpis::app {

Image::Image(int width, int height, Color fill) : w(width), h(height), px(std::size_t(width) * height * 3) {
  for (std::size_t i = 0; i < px.size(); i += 3) {
    px[i] = fill.r;
    px[i + 1] = fill.g;
    px[i + 2] = fill.b;
  }
}

void Image::blend(int x, int y, Color c, float a) {
  if (x < 0 || y < 0 || x >= w || y >= h) return;
  float* p = &px[(std::size_t(y) * w + x) * 3];
  p[0] += (c.r - p[0]) * a;
  p[1] += (c.g - p[1]) * a;
  p[2] += (c.b - p[2]) * a;
}

void Image::disc(float cx, float cy, float r, Color c) {
  for (int y = int(std::floor(cy - r)); y <= int(std::ceil(cy + r)); ++y)
    for (int x = int(std::floor(cx - r)); x <= int(std::ceil(cx + r)); ++x) {
      const float dx = x + 0.5f - cx, dy = y + 0.5f - cy;
      if (dx * dx + dy * dy <= r * r) blend(x, y, c);
    }
}

void Image::ring(float cx, float cy, float r, float thickness, Color c) {
  const float ro = r + thickness;
  for (int y = int(std::floor(cy - ro)); y <= int(std::ceil(cy + ro)); ++y)
    for (int x = int(std::floor(cx - ro)); x <= int(std::ceil(cx + ro)); ++x) {
      const float d = std::hypot(x + 0.5f - cx, y + 0.5f - cy);
      if (d >= r && d <= ro) blend(x, y, c);
    }
}

void Image::plus(float cx, float cy, int arm, int thickness, Color c) {
  for (int t = -thickness / 2; t <= thickness / 2; ++t)
    for (int i = -arm; i <= arm; ++i) {
      blend(int(cx) + i, int(cy) + t, c);
      blend(int(cx) + t, int(cy) + i, c);
    }
}

void Image::line(float x0, float y0, float x1, float y1, Color c, float a, int dash) {
  const int steps = std::max(1, int(std::ceil(std::max(std::fabs(x1 - x0), std::fabs(y1 - y0)))));
  for (int i = 0; i <= steps; ++i) {
    if (dash > 0 && (i / dash) % 2 == 1) continue;
    const float t = float(i) / steps;
    blend(int(x0 + (x1 - x0) * t), int(y0 + (y1 - y0) * t), c, a);
  }
}

const std::vector<std::array<int, 3>>& inferno_stops() {
  static const std::vector<std::array<int, 3>> stops{{0, 0, 4},      {31, 12, 72},   {85, 15, 109},
                                                      {136, 34, 106}, {186, 54, 85},  {227, 89, 51},
                                                      {249, 140, 10}, {249, 201, 50}, {252, 255, 164}};
  return stops;
}

Color inferno(double t) {
  const auto& stops = inferno_stops();
  t = std::clamp(t, 0.0, 1.0) * double(stops.size() - 1);
  const std::size_t i = std::min(stops.size() - 2, static_cast<std::size_t>(t));
  const double f = t - double(i);
  auto channel = [&](int c) { return float((stops[i][c] * (1 - f) + stops[i + 1][c] * f) / 255); };
  return {channel(0), channel(1), channel(2)};
}

double srgb_encode(double linear) {
  const double x = std::clamp(linear, 0.0, 1.0);
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
}

void write_png(const std::string& path, const Image& img) {
  write_image_file(path, img.w, img.h, 3, img.px.data());  // 8-bit: clamped to [0, 1] and rounded
}

}  // namespace envpis::app
