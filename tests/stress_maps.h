// SPDX-License-Identifier: Apache-2.0
// The sun stress family: lat-long skies with small, very bright discs where samplers break: on the
// lat-long seam, at the poles, on the horizon, on top-cell boundaries and corners of the default 12 x 12
// table, inside one fine texel, and two suns of very different size. Generated, never shipped; used by
// the tests and by bench/stress_maps (which writes them as EXR for scripts/stress-bench.sh).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "envpis/envpis.h"

namespace envpis::test {

struct Sun {
  Vec3 direction;        ///< map space, unit
  float radius_degrees;  ///< angular radius
  float radiance;
};

struct StressMap {
  std::string name;
  std::vector<Sun> suns;
};

/// Map-space direction of the world equal-area square point p. The suns are placed in map space; the
/// table's cell grid is symmetric under the lat-long orientation's mirror, so boundaries and corners
/// stay boundaries and corners in either orientation.
inline Vec3 square_point(float x, float y) { return equal_area_square_to_sphere({x, y}); }

inline Vec3 polar(float theta_degrees, float phi_degrees) {
  const float t = theta_degrees * kPi / 180, p = phi_degrees * kPi / 180;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

inline std::vector<StressMap> stress_family() {
  return {
      {"seam", {{polar(60, 0.05f), 0.5f, 1e5f}}},
      {"north-pole", {{polar(0.3f, 40), 0.4f, 1e5f}}},
      {"south-pole", {{polar(179.5f, 200), 0.8f, 4e4f}}},
      {"horizon", {{polar(90, 123), 0.25f, 5e5f}}},
      {"cell-edge", {{square_point(5.0f / 12, 0.37f), 0.3f, 2e5f}}},
      {"cell-corner", {{square_point(4.0f / 12, 8.0f / 12), 0.2f, 5e5f}}},
      {"quadrant", {{square_point(0.5f, 0.2f), 0.6f, 1e5f}}},
      {"subtexel", {{polar(50, 250), 0.1f, 1e6f}}},
      {"wide-sun", {{polar(40, 300), 2.0f, 1e3f}}},
      {"two-suns", {{polar(30, 80), 0.15f, 1e6f}, {polar(70, 200), 2.0f, 2e3f}}},
  };
}

/// Issue 23's quadrant symptom: a sun of radius 0.5 degrees, 45 degrees up, on each of the four
/// half-lines between the equal-area square's top-level quadrants (x = 1/2 or y = 1/2). Written by
/// bench/envpis_stress_maps next to the family above; not part of the tests' family.
inline std::vector<StressMap> quadrant_boundary_family() {
  const float r = std::sqrt(1.0f - std::sqrt(0.5f));  // the square's radius of cos(theta) = sqrt(1/2)
  const float lo = 0.5f - 0.5f * r, hi = 0.5f + 0.5f * r;
  return {{"quadrant45-a", {{square_point(0.5f, lo), 0.5f, 1e5f}}},
          {"quadrant45-b", {{square_point(lo, 0.5f), 0.5f, 1e5f}}},
          {"quadrant45-c", {{square_point(0.5f, hi), 0.5f, 1e5f}}},
          {"quadrant45-d", {{square_point(hi, 0.5f), 0.5f, 1e5f}}}};
}

/// A w x h lat-long sky (a smooth gradient, brighter at the zenith) with the suns, each texel the
/// average over 4 x 4 points so that sub-texel suns keep their energy.
inline EnvironmentMap make_stress_map(const StressMap& m, int w = 1024, int h = 512,
                                      const EnvironmentMapOptions& options = {}) {
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
  std::vector<float> cos_r;
  for (const Sun& s : m.suns) cos_r.push_back(std::cos(s.radius_degrees * kPi / 180));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double acc = 0;
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
          const Vec3 d = latlong_to_direction({(x + (i + 0.5f) / 4) / w, (y + (j + 0.5f) / 4) / h});
          double v = 0.5 + 0.8 * std::max(0.0f, d.z);
          for (std::size_t k = 0; k < m.suns.size(); ++k)
            if (dot(d, m.suns[k].direction) >= cos_r[k]) v += m.suns[k].radiance;
          acc += v;
        }
      for (int c = 0; c < 3; ++c) rgb[(static_cast<std::size_t>(y) * w + x) * 3 + c] = static_cast<float>(acc / 16);
    }
  return EnvironmentMap::from_pixels(w, h, std::move(rgb), options);
}

}  // namespace envpis::test
