// SPDX-License-Identifier: Apache-2.0
#include "table_pictures.h"

#include <algorithm>
#include <cmath>

namespace envpis::app {

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
      img.blend(x, y, {float(srgb_encode(c.r * k)), float(srgb_encode(c.g * k)), float(srgb_encode(c.b * k))});
    }
  return img;
}

// From the 0.5th percentile (at most six decades below the top) to the 99.9th percentile (so the sky
// is not crushed by a tiny sun, which saturates to the colormap's white end).
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
  auto ring_at = [&](Vec3 axis, float radius, Color c) {
    const Point2 p = at(axis);
    img.ring(p.x, p.y, radius, th, c);
  };
  if (proxy->kd > 0) ring_at(proxy->n, r, {0.2f, 1.0f, 0.2f});
  if (proxy->kt > 0) ring_at(-proxy->n, r, {0.2f, 1.0f, 0.2f});
  if (proxy->wr > 0) ring_at(proxy->r, r * 1.4f, {0.1f, 0.9f, 1.0f});
  if (proxy->wt > 0) ring_at(proxy->t, r * 1.8f, {1.0f, 0.2f, 1.0f});
}

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

}  // namespace envpis::app
