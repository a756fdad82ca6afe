// SPDX-License-Identifier: Apache-2.0
// Shared helpers for the tests: synthetic maps, the blender-data maps, a fixed-seed RNG, a scratch
// directory.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "envpis/envpis.h"

namespace envpis::test {

/// The bytes of an OpenEXR file with its data and display windows rewritten to claim width x height
/// texels (the pixel data stays as it was); empty when the file has no such attributes.
inline std::string exr_claiming(std::string exr, int width, int height) {
  for (const std::string key : {std::string("dataWindow\0box2i\0", 17), std::string("displayWindow\0box2i\0", 20)}) {
    const std::size_t at = exr.find(key);
    if (at == std::string::npos || at + key.size() + 4 + 16 > exr.size()) return {};
    const std::int32_t box[4] = {0, 0, width - 1, height - 1};
    std::memcpy(&exr[at + key.size() + 4], box, sizeof box);  // after the attribute's 4-byte size
  }
  return exr;
}

/// Directory of Debian's blender-data studio-light HDRIs (1024x512 lat-long EXR).
inline std::string blender_world_dir() { return "/usr/share/blender/datafiles/studiolights/world"; }

inline std::vector<std::string> blender_map_names() {
  return {"sunrise", "sunset", "studio", "interior", "city", "courtyard", "forest", "night"};
}

inline std::string blender_map(const std::string& name) { return blender_world_dir() + "/" + name + ".exr"; }

inline bool have_blender_maps() { return std::filesystem::exists(blender_map("sunset")); }

/// A lat-long map w x h whose texel (x, y) has radiance f(x, y) in all channels.
template <class F>
EnvironmentMap synthetic_latlong(int w, int h, F f, const EnvironmentMapOptions& opt = {}) {
  std::vector<float> px(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float v = f(x, y);
      for (int c = 0; c < 3; ++c) px[(static_cast<std::size_t>(y) * w + x) * 3 + c] = v;
    }
  return EnvironmentMap::from_pixels(w, h, std::move(px), opt);
}

/// A sky-like lat-long test map: a dim gradient, a small very bright "sun" and a bright band.
inline EnvironmentMap synthetic_sky(int w = 256, int h = 128) {
  return synthetic_latlong(w, h, [w, h](int x, int y) {
    float v = 0.2f + 0.8f * float(h - y) / h;
    if (std::abs(x - w / 3) <= 1 && std::abs(y - h / 4) <= 1) v = 5000.0f;  // sun
    if (y > h / 2 && y < h / 2 + h / 16) v += 20.0f;                         // horizon band
    return v;
  });
}

/// A fresh directory under the system's temporary directory (one per object: the process id and a
/// counter name it), removed with everything in it when the object goes.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static int count = 0;
    path = std::filesystem::temp_directory_path() /
           ("envpis-test-" + std::to_string(::getpid()) + "-" + std::to_string(count++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  /// Writes `text` to the file `name` in the directory; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = path / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

/// Uniform random unit vector.
inline Vec3 random_direction(std::mt19937_64& rng) {
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  const float z = 1 - 2 * U(rng), phi = 2 * kPi * U(rng), r = std::sqrt(std::max(0.0f, 1 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// A table with 4 x 4 sub-cells per top cell, and a product sampler that refines into them with the
/// moments cell estimate: the refined configuration the cache tests share.
inline ImportanceTableOptions refined_table() {
  ImportanceTableOptions o;
  o.subdivision = 4;
  return o;
}

inline ProductSamplerOptions refined_sampler() {
  ProductSamplerOptions o;
  o.refine = true;
  o.cell_estimate = CellEstimate::Moments;
  return o;
}

}  // namespace envpis::test
