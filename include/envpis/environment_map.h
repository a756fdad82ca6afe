// An HDR environment map: linear RGB radiance over the sphere of directions, read from the user's
// own image file and evaluated with bilinear filtering of its pixels.
//
// Conventions: +Z is up. A lat-long (equirectangular) image maps column u in [0,1) to the azimuth
// phi = 2 pi u measured from +X towards +Y, and row v in [0,1] to the polar angle theta = pi v from
// +Z (top row = zenith). An equal-area image is Clarberg's octahedral square (see equal_area.h).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "envpis/common.h"

namespace envpis {

enum class MapLayout {
  Auto,       ///< square image -> EqualArea, anything else -> LatLong (warns unless width == 2 height)
  LatLong,    ///< equirectangular
  EqualArea,  ///< Clarberg equal-area square (width must equal height)
};

/// Parses "auto", "latlong" or "equal-area"; throws Error otherwise.
MapLayout parse_map_layout(const std::string& s);
const char* to_string(MapLayout layout);

struct EnvironmentMapOptions {
  MapLayout layout = MapLayout::Auto;
  float scale = 1.0f;  ///< multiplies every texel (must be finite and >= 0)
  Mat3 rotation;       ///< world = rotation * map direction (default identity)
};

/// What load() had to repair. Policy: a texel channel that is NaN, infinite or negative is replaced by
/// 0 (an infinite or negative radiance has no physical meaning and would poison every pixel that sees
/// it); the counts let callers warn. After the scale, channels are clamped to 1e30 so that sums and
/// filtering stay finite.
struct MapLoadReport {
  std::size_t nan_texels = 0;
  std::size_t inf_texels = 0;
  std::size_t negative_texels = 0;
  std::size_t repaired() const { return nan_texels + inf_texels + negative_texels; }
};

class EnvironmentMap {
 public:
  /// Loads an OpenEXR, Radiance HDR (or any other format OpenImageIO reads) file. Throws Error naming
  /// the file and the reason when it is missing, unreadable, corrupt, truncated or has no pixels.
  static EnvironmentMap load(const std::string& path, const EnvironmentMapOptions& options = {});

  /// Builds a map from interleaved RGB floats (width * height * 3), e.g. a synthetic test map.
  /// Non-finite and negative values are repaired as in load().
  static EnvironmentMap from_pixels(int width, int height, std::vector<float> rgb,
                                    const EnvironmentMapOptions& options = {});

  /// Radiance arriving from world direction `d` (need not be normalized). Zero for an invalid d.
  Rgb eval(Vec3 d) const;

  /// Radiance at map-local texture coordinates (lat-long u,v or equal-area square x,y), bilinear.
  Rgb eval_texture(Point2 uv) const;

  /// Direction in map space <-> world space.
  Vec3 to_world(Vec3 map_dir) const { return rotation_ * map_dir; }
  Vec3 to_map(Vec3 world_dir) const { return inverse_rotation_ * world_dir; }

  int width() const { return width_; }
  int height() const { return height_; }
  MapLayout layout() const { return layout_; }
  float scale() const { return scale_; }
  const std::string& path() const { return path_; }
  const MapLoadReport& load_report() const { return report_; }
  /// Texel (x, y) after repair and scale.
  Rgb texel(int x, int y) const {
    const float* p = &pixels_[(static_cast<std::size_t>(y) * width_ + x) * 3];
    return {p[0], p[1], p[2]};
  }
  std::size_t bytes_used() const { return pixels_.capacity() * sizeof(float) + sizeof(*this); }

 private:
  EnvironmentMap() = default;
  void finish(const EnvironmentMapOptions& options);
  Rgb bilinear_latlong(float u, float v) const;
  Rgb bilinear_equal_area(float x, float y) const;

  int width_ = 0, height_ = 0;
  MapLayout layout_ = MapLayout::LatLong;
  float scale_ = 1.0f;
  Mat3 rotation_, inverse_rotation_;
  std::vector<float> pixels_;  // RGB, row-major, top row first
  std::string path_;
  MapLoadReport report_;
};

/// Direction (map space, +Z up) <-> lat-long texture coordinates in [0,1]^2.
Point2 direction_to_latlong(Vec3 d);
Vec3 latlong_to_direction(Point2 uv);

}  // namespace envpis
