// SPDX-License-Identifier: Apache-2.0
// An HDR environment map: linear RGB radiance over the sphere of directions, read from the user's
// own image file and evaluated with bilinear filtering of its pixels (or nearest-texel look-up).
//
// Conventions: +Z is up. A lat-long (equirectangular) image maps row v in [0,1] to the polar angle
// theta = pi v from +Z (top row = zenith), and by default (LatLongOrientation::Panorama, the convention
// of Blender/Cycles) column u to the world direction of azimuth phi (from +X towards +Y) with
// u = 0.5 - phi / (2 pi): +X is the image's centre column, +Y is at u = 0.25, -Y at u = 0.75. Seen
// from inside the sphere the panorama then looks like the photograph, as in other renderers and
// panorama viewers. LatLongOrientation::Legacy is envpis's earlier u = phi / (2 pi), which shows every
// photograph mirrored. An equal-area image is
// Clarberg's octahedral square (see equal_area.h); the orientation does not apply to it.
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

/// Which way a lat-long image's columns run around +Z (see the file comment).
enum class LatLongOrientation {
  Panorama,  ///< u = 0.5 - phi / (2 pi): +X at u = 0.5, +Y at u = 0.25 (Blender/Cycles)
  Legacy,    ///< u = phi / (2 pi): +X at u = 0, +Y at u = 0.25 (envpis before; mirrors photographs)
};

/// Parses "panorama" or "legacy"; throws Error otherwise.
LatLongOrientation parse_latlong_orientation(const std::string& s);
const char* to_string(LatLongOrientation orientation);

/// How eval() reads between texel centres. Nearest gives the image's values as they are (a map with
/// hard-edged regions, comparisons with renderers set to such a look-up), and a radiance that is
/// constant over each texel, as the texels of an importance table built from the image are.
enum class MapFilter {
  Bilinear,  ///< bilinear interpolation of the four nearest texels (smooth; the default)
  Nearest,   ///< the texel the direction falls in: piecewise constant, exactly the image's values
};

/// Parses "bilinear" or "nearest"; throws Error otherwise.
MapFilter parse_map_filter(const std::string& s);
const char* to_string(MapFilter filter);

struct EnvironmentMapOptions {
  MapLayout layout = MapLayout::Auto;
  float scale = 1.0f;  ///< multiplies every texel (must be finite and >= 0)
  Mat3 rotation;  ///< world = rotation * the direction a texel has under `orientation` (default identity)
  LatLongOrientation orientation = LatLongOrientation::Panorama;  ///< lat-long maps only
  MapFilter filter = MapFilter::Bilinear;
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
  /// The reader that decoded the file: OpenImageIO's ("openexr", "hdr", "pnm", "tiff", ...) or "png"
  /// (libpng itself, never OpenImageIO's PNG reader); empty for from_pixels().
  std::string format;
  /// The reader the file's extension names (empty: none). It differs from `format` when the extension
  /// is wrong (an OpenEXR file named .png): load() goes by the content for OpenEXR, Radiance HDR, PFM,
  /// TIFF and PNG, and by the extension for anything else.
  std::string extension_format;
};

/// A texel of a map image: column x, row y (top row 0).
struct TexelCoord {
  int x = 0, y = 0;
};

class EnvironmentMap {
 public:
  /// Loads an OpenEXR, Radiance HDR (or any other format OpenImageIO reads) file. Throws Error naming
  /// the file and the reason when it is missing, not a regular file, unreadable, of an unknown format,
  /// corrupt, truncated, too large or has no pixels.
  ///
  /// The reader is chosen by the file's first bytes for OpenEXR, Radiance HDR, PFM, TIFF and PNG (so a
  /// wrong extension is harmless, and reported by warnings()), and by the extension for any other
  /// format OpenImageIO reads. OpenImageIO's fallback of offering a file to every reader is not used.
  static EnvironmentMap load(const std::string& path, const EnvironmentMapOptions& options = {});

  /// Builds a map from interleaved RGB floats (width * height * 3), e.g. a synthetic test map.
  /// Non-finite and negative values are repaired as in load().
  static EnvironmentMap from_pixels(int width, int height, std::vector<float> rgb,
                                    const EnvironmentMapOptions& options = {});

  /// Radiance arriving from world direction `d` (need not be normalized). Zero for an invalid d.
  /// The same as eval_texture(texture_coord(d)).
  Rgb eval(Vec3 d) const;

  /// Where world direction `d` (need not be normalized) reads the image: lat-long (u, v) or equal-area
  /// (x, y) texture coordinates. NaN for an invalid d. A renderer that needs both the radiance and an
  /// ImportanceTable's pdf of one direction computes this once and hands it to both (eval_texture and
  /// ImportanceTable::pdf(d, texture)).
  Point2 texture_coord(Vec3 d) const;

  /// Radiance at map-local texture coordinates (lat-long u,v or equal-area square x,y), read with
  /// filter().
  Rgb eval_texture(Point2 uv) const;

  /// Direction in map space <-> world space. Map space is the frame of the texture-coordinate
  /// functions: direction_to_latlong(to_map(d)) or equal_area_sphere_to_square(to_map(d)) is where
  /// world direction d reads the image, and to_world(latlong_to_direction(uv)) is the world direction
  /// of (u, v). The transform is the option's rotation, and for a lat-long map in the Panorama
  /// orientation also the mirror x -> -x (Panorama is Legacy of the mirrored direction, since
  /// atan2(y, -x) = pi - atan2(y, x)); it is then orthogonal with determinant -1. Keeping the
  /// orientation here gives every look-up (eval, ImportanceTable) one lat-long formula.
  Vec3 to_world(Vec3 map_dir) const { return to_world_ * map_dir; }
  Vec3 to_map(Vec3 world_dir) const { return to_map_ * world_dir; }

  int width() const { return width_; }
  int height() const { return height_; }
  MapLayout layout() const { return layout_; }
  float scale() const { return scale_; }
  /// The orientation option (it only affects lat-long maps).
  LatLongOrientation orientation() const { return orientation_; }
  /// How eval() and eval_texture() read the texels.
  MapFilter filter() const { return filter_; }
  const std::string& path() const { return path_; }
  const MapLoadReport& load_report() const { return report_; }
  /// Largest texel channel after repair and scale; 0 for an all-black map.
  float max_radiance() const { return max_radiance_; }
  /// No texel has positive radiance (the ImportanceTable of such a map is empty).
  bool is_black() const { return !(max_radiance_ > 0); }
  /// One-line warnings about this map for a tool to print (each names the file): repaired texels,
  /// a file extension naming another format than the content's, a lat-long map that is not 2:1.
  /// Empty when there is nothing to say. (An all-black map is for the caller to judge: is_black().)
  std::vector<std::string> warnings() const;
  /// The texel that texture point uv (lat-long u, v or equal-area x, y) lies in: the one a Nearest
  /// look-up returns. Outside [0,1) a lat-long map wraps in u and clamps in v; an equal-area map wraps
  /// across its edges as the sphere does. Non-finite uv give texel (0, 0).
  TexelCoord texel_coord(Point2 uv) const;
  /// Texel (x, y) after repair and scale.
  Rgb texel(int x, int y) const {
    const float* p = &pixels_[(static_cast<std::size_t>(y) * width_ + x) * 3];
    return {p[0], p[1], p[2]};
  }
  std::size_t bytes_used() const { return pixels_.capacity() * sizeof(float) + sizeof(*this); }
  /// Starts fetching the texels eval_texture(uv) reads into the cache, for a caller that reads them
  /// later (a texel of a large map is rarely in cache). A hint: it changes no result.
  void prefetch(Point2 uv) const;

 private:
  EnvironmentMap() = default;
  void finish(const EnvironmentMapOptions& options);
  Rgb bilinear_latlong(float u, float v) const;
  Rgb bilinear_equal_area(float x, float y) const;

  int width_ = 0, height_ = 0;
  MapLayout layout_ = MapLayout::LatLong;
  float scale_ = 1.0f;
  LatLongOrientation orientation_ = LatLongOrientation::Panorama;
  MapFilter filter_ = MapFilter::Bilinear;
  float max_radiance_ = 0;
  Mat3 to_world_, to_map_;
  std::vector<float> pixels_;  // RGB, row-major, top row first
  std::string path_;
  MapLoadReport report_;
};

/// Direction in map space (+Z up; see EnvironmentMap::to_map) <-> lat-long texture coordinates in
/// [0,1]^2: u = phi / (2 pi) with phi the azimuth from +X towards +Y, v = theta / pi. The map's
/// orientation lives in to_map / to_world, so this is the one lat-long formula for both orientations.
Point2 direction_to_latlong(Vec3 d);
Vec3 latlong_to_direction(Point2 uv);
/// The texel of a width x height lat-long image that texture point uv lies in (wraps in u, clamps in
/// v): EnvironmentMap::texel_coord of a lat-long map. Non-finite uv give texel (0, 0).
TexelCoord latlong_texel(Point2 uv, int width, int height);

}  // namespace envpis
