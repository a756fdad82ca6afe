// SPDX-License-Identifier: Apache-2.0
// The table's peak bound (src/texel_peak.cpp) against the algorithm it replaced
// (tests/texel_peak_reference.h): bit-identical peaks, and bit-identical table values, on maps made to
// break it: tiny suns at the seam, the poles and cell corners, single-texel spikes, nearest and bilinear
// look-ups, rotated and equal-area maps, and grids from 1 to 732 texels per side.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "envpis/envpis.h"
#include "stress_maps.h"
#include "texel_peak.h"
#include "texel_peak_reference.h"

namespace envpis {
namespace {

// The per-texel importance the table build feeds the bound (texel_importance.cpp's Setup).
std::vector<float> channel_average(const EnvironmentMap& m) {
  std::vector<float> lum(static_cast<std::size_t>(m.width()) * m.height());
  for (int y = 0; y < m.height(); ++y)
    for (int x = 0; x < m.width(); ++x) {
      const Rgb L = m.texel(x, y);
      lum[static_cast<std::size_t>(y) * m.width() + x] = static_cast<float>((double(L.r) + L.g + L.b) / 3.0);
    }
  return lum;
}

// A dark map with single bright texels where the bound's look-ups wrap or clamp: both ends of the seam,
// the first and last rows (the poles), the centre, and random ones.
EnvironmentMap spike_map(int w, int h, const EnvironmentMapOptions& options, unsigned seed) {
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3, 0.01f);
  std::mt19937 rng(seed);
  std::vector<std::pair<int, int>> at = {{0, h / 3}, {w - 1, h / 2}, {w / 3, 0}, {w / 2, h - 1}, {w / 2, h / 2}};
  for (int k = 0; k < 12; ++k) at.push_back({int(rng() % unsigned(w)), int(rng() % unsigned(h))});
  for (auto [x, y] : at)
    for (int c = 0; c < 3; ++c) rgb[(static_cast<std::size_t>(y) * w + x) * 3 + c] = 1e5f * float(1 + (x + y) % 7);
  return EnvironmentMap::from_pixels(w, h, std::move(rgb), options);
}

// Number of texels whose peaks differ in any bit (0 when the two are the same floats).
std::size_t differing(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
  return n;
}

struct Case {
  std::string name;
  EnvironmentMap map;
};

std::vector<Case> adversarial_maps() {
  std::vector<Case> cases;
  EnvironmentMapOptions nearest;
  nearest.filter = MapFilter::Nearest;
  EnvironmentMapOptions rotated;  // a rotation that is not about +Z: every outline is tilted
  const float c = std::cos(0.7f), s = std::sin(0.7f);
  rotated.rotation.m[0][0] = c, rotated.rotation.m[0][2] = s, rotated.rotation.m[2][0] = -s,
  rotated.rotation.m[2][2] = c;
  for (const test::StressMap& sm : test::stress_family()) {
    cases.push_back({sm.name, test::make_stress_map(sm, 256, 128)});
    cases.push_back({sm.name + " nearest", test::make_stress_map(sm, 256, 128, nearest)});
  }
  cases.push_back({"spikes", spike_map(512, 256, {}, 1)});
  cases.push_back({"spikes nearest", spike_map(512, 256, nearest, 2)});
  cases.push_back({"spikes rotated", spike_map(300, 150, rotated, 3)});
  EnvironmentMapOptions equal_area;
  equal_area.layout = MapLayout::EqualArea;
  cases.push_back({"spikes equal-area", spike_map(200, 200, equal_area, 4)});
  equal_area.rotation = rotated.rotation;
  cases.push_back({"spikes equal-area rotated", spike_map(200, 200, equal_area, 5)});
  return cases;
}

TEST(TexelPeak, SameBitsAsTheMaxTreeAlgorithm) {
  for (const Case& c : adversarial_maps()) {
    const std::vector<float> lum = channel_average(c.map);
    for (int N : {1, 2, 3, 12, 97, 256, 732}) {
      const std::vector<float> ours = detail::texel_peaks(c.map, lum, N);
      const std::vector<float> old = test::old_peak::texel_peaks(c.map, lum, N);
      EXPECT_EQ(differing(ours, old), 0u) << c.name << ", N = " << N;
    }
  }
}

TEST(TexelPeak, TableValuesAreTheOldBoundApplied) {
  // With the floor off, a bounded table's texels are max(unbounded, old peak / K), float for float:
  // the bound applied in place gives the values the old separate array did.
  EnvironmentMapOptions nearest;
  nearest.filter = MapFilter::Nearest;
  std::vector<Case> cases;
  cases.push_back({"north-pole", test::make_stress_map(test::stress_family()[1], 512, 256)});
  cases.push_back({"cell-corner nearest", test::make_stress_map(test::stress_family()[5], 512, 256, nearest)});
  cases.push_back({"spikes", spike_map(512, 256, {}, 7)});
  for (const Case& c : cases) {
    ImportanceTableOptions o;
    o.floor = 0;
    o.fine_resolution = 360;
    ImportanceTableOptions off = o;
    off.peak_ratio = 0;
    const ImportanceTable bounded(c.map, o), unbounded(c.map, off);
    const int N = bounded.fine_resolution();
    ASSERT_EQ(N, unbounded.fine_resolution());
    const std::vector<float> old = test::old_peak::texel_peaks(c.map, channel_average(c.map), N);
    const float inv_k = 1.0f / o.peak_ratio;
    std::vector<float> expect, got;
    std::size_t raised = 0;
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) {
        const float v = unbounded.importance(x, y), p = old[static_cast<std::size_t>(y) * N + x] * inv_k;
        raised += p > v;
        expect.push_back(std::max(v, p));
        got.push_back(bounded.importance(x, y));
      }
    EXPECT_GT(raised, 0u) << c.name;  // the bound does something on these maps
    EXPECT_EQ(differing(got, expect), 0u) << c.name;
  }
}

}  // namespace
}  // namespace envpis
