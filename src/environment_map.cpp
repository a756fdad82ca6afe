// SPDX-License-Identifier: Apache-2.0
#include "envpis/environment_map.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>

#include "envpis/equal_area.h"
#include "image_format.h"
#include "texel_filter.h"

#define ENVPIS_KERNEL_NS scalar
#include "simd_ops.h"

namespace envpis {

namespace {
constexpr float kMaxRadiance = 1e30f;
}  // namespace

MapLayout parse_map_layout(const std::string& s) {
  if (s == "auto") return MapLayout::Auto;
  if (s == "latlong" || s == "lat-long" || s == "equirect") return MapLayout::LatLong;
  if (s == "equal-area" || s == "equalarea") return MapLayout::EqualArea;
  throw Error("unknown map layout '" + s + "' (expected auto, latlong or equal-area)");
}

const char* to_string(MapLayout layout) {
  switch (layout) {
    case MapLayout::Auto: return "auto";
    case MapLayout::LatLong: return "latlong";
    case MapLayout::EqualArea: return "equal-area";
  }
  return "?";
}

LatLongOrientation parse_latlong_orientation(const std::string& s) {
  if (s == "panorama") return LatLongOrientation::Panorama;
  if (s == "legacy") return LatLongOrientation::Legacy;
  throw Error("unknown lat-long orientation '" + s + "' (expected panorama or legacy)");
}

const char* to_string(LatLongOrientation orientation) {
  return orientation == LatLongOrientation::Legacy ? "legacy" : "panorama";
}

MapFilter parse_map_filter(const std::string& s) {
  if (s == "bilinear") return MapFilter::Bilinear;
  if (s == "nearest") return MapFilter::Nearest;
  throw Error("unknown map filter '" + s + "' (expected bilinear or nearest)");
}

const char* to_string(MapFilter filter) { return filter == MapFilter::Nearest ? "nearest" : "bilinear"; }

// Both angles by the polynomial atan2 (simd_ops.h): a few times cheaper than the library's atan2f and
// acosf, which were about a seventh of a render's time. Max error against the exact angles, measured
// over the whole sphere (tests/test_environment_map.cpp, LatLongLookUpIsAccurate): 6.5e-7 rad in phi
// (mostly u's own float rounding near 1), 3.5e-7 rad in theta: under 4e-4 of a texel of a 4096 x 2048
// map, so a nearest look-up picks the exact texel except within 1e-3 of a texel of its edges. The polar angle as
// atan2(sqrt(x^2 + y^2), z) needs no normalisation and keeps its precision near the poles, where
// acos(z) of a rounded z loses half its digits. The table's gather reads the map through this same
// function (texel_importance.cpp), so its importance and eval agree.
Point2 direction_to_latlong(Vec3 d) {
  float phi = detail::scalar::simd::atan2_fast(d.y, d.x);
  if (phi < 0) phi += 2 * kPi;
  float u = phi * (0.5f * kInvPi);
  if (u >= 1.0f) u -= 1.0f;
  const float theta = detail::scalar::simd::atan2_fast(std::sqrt(d.x * d.x + d.y * d.y), d.z);
  return {u, theta * kInvPi};
}

Vec3 latlong_to_direction(Point2 uv) {
  const float phi = uv.x * 2 * kPi, theta = uv.y * kPi;
  const float s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

EnvironmentMap EnvironmentMap::from_pixels(int width, int height, std::vector<float> rgb,
                                           const EnvironmentMapOptions& options) {
  if (width <= 0 || height <= 0) throw Error("environment map size must be positive");
  if (rgb.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3)
    throw Error("environment map pixel array has the wrong size");
  EnvironmentMap map;
  map.width_ = width;
  map.height_ = height;
  map.pixels_ = std::move(rgb);
  map.finish(options);
  return map;
}

void EnvironmentMap::finish(const EnvironmentMapOptions& options) {
  if (!(options.scale >= 0.0f) || !std::isfinite(options.scale))
    throw Error("environment map scale must be finite and >= 0");
  layout_ = options.layout;
  if (layout_ == MapLayout::Auto) layout_ = width_ == height_ ? MapLayout::EqualArea : MapLayout::LatLong;
  if (layout_ == MapLayout::EqualArea && width_ != height_)
    throw Error("an equal-area environment map must be square, got " + std::to_string(width_) + "x" +
                std::to_string(height_));
  scale_ = options.scale;
  orientation_ = options.orientation;
  filter_ = options.filter;
  // to_world = rotation * mirror(x -> -x) for a Panorama lat-long map: the mirror negates the
  // rotation's first column. (See to_world in the header for why the orientation lives here.)
  to_world_ = options.rotation;
  if (layout_ == MapLayout::LatLong && orientation_ == LatLongOrientation::Panorama)
    for (auto& row : to_world_.m) row[0] = -row[0];
  to_map_ = to_world_.transposed();
  max_radiance_ = 0;
  for (float& v : pixels_) {
    if (std::isnan(v)) {
      ++report_.nan_texels;
      v = 0;
    } else if (std::isinf(v)) {
      ++report_.inf_texels;
      v = 0;
    } else if (v < 0) {
      ++report_.negative_texels;
      v = 0;
    }
    v = std::min(v * scale_, kMaxRadiance);  // also catches a huge texel * scale overflowing to inf
    max_radiance_ = std::max(max_radiance_, v);
  }
}

std::vector<std::string> EnvironmentMap::warnings() const {
  std::vector<std::string> w;
  const std::string name = path_.empty() ? std::string("the environment map") : "'" + path_ + "'";
  if (report_.repaired() > 0)
    w.push_back(name + ": " + std::to_string(report_.repaired()) + " texel values were invalid and set to 0 (" +
                std::to_string(report_.nan_texels) + " NaN, " + std::to_string(report_.inf_texels) +
                " infinite, " + std::to_string(report_.negative_texels) + " negative)");
  if (!report_.format.empty() && !report_.extension_format.empty() && report_.format != report_.extension_format) {
    const char* is = detail::format_display_name(report_.format);
    const std::string ext = detail::lower(std::filesystem::path(path_).extension().string());
    w.push_back(name + " contains " + (is ? is : report_.format.c_str()) + " data despite its '" + ext +
                "' extension: read as " + (is ? is : report_.format.c_str()));
  }
  if (layout_ == MapLayout::LatLong && width_ != 2 * height_)
    w.push_back(name + " is read as lat-long but is " + std::to_string(width_) + "x" + std::to_string(height_) +
                ", not 2:1");
  return w;
}

Rgb EnvironmentMap::bilinear_latlong(float u, float v) const {
  return detail::bilinear_latlong([this](int x, int y) { return texel(x, y); }, width_, height_, u, v);
}

Rgb EnvironmentMap::bilinear_equal_area(float x, float y) const {
  return detail::bilinear_equal_area([this](int i, int j) { return texel(i, j); }, width_, x, y);
}

TexelCoord latlong_texel(Point2 uv, int width, int height) {
  // Every direction's look-up lands here (u in [0, 1), v in [0, 1]): without floor, the same texel as
  // below (truncation is floor for these non-negative products; u * width can round up to width).
  if (uv.x >= 0.0f && uv.x < 1.0f && uv.y >= 0.0f && uv.y <= 1.0f) {
    const int xi = static_cast<int>(uv.x * width);
    return {xi < width ? xi : xi - width, std::min(static_cast<int>(uv.y * height), height - 1)};
  }
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {};
  const float fx = std::floor(uv.x * width), fy = std::floor(uv.y * height);
  // Far outside the image (only for absurd inputs) the float -> int conversion must not overflow.
  int xi = static_cast<int>(std::clamp(fx, -2.0f * width, 2.0f * width));
  const int yi = static_cast<int>(std::clamp(fy, -1.0f, float(height)));
  // xi is in [-2w, 2w]: at most two steps of wrapping, without an integer division per look-up.
  while (xi >= width) xi -= width;
  while (xi < 0) xi += width;
  return {xi, std::clamp(yi, 0, height - 1)};
}

TexelCoord EnvironmentMap::texel_coord(Point2 uv) const {
  if (layout_ == MapLayout::LatLong) return latlong_texel(uv, width_, height_);
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {};
  int xi = static_cast<int>(std::clamp(std::floor(uv.x * width_), -2.0f * width_, 2.0f * width_));
  int yi = static_cast<int>(std::clamp(std::floor(uv.y * height_), -2.0f * height_, 2.0f * height_));
  if (!equal_area_wrap(width_, xi, yi)) {  // wraps across the square's edges as the sphere does
    xi = std::clamp(xi, 0, width_ - 1);
    yi = std::clamp(yi, 0, height_ - 1);
  }
  return {xi, yi};
}

Rgb EnvironmentMap::eval_texture(Point2 uv) const {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {};
  if (filter_ == MapFilter::Nearest) {
    const TexelCoord t = texel_coord(uv);
    return texel(t.x, t.y);
  }
  return layout_ == MapLayout::EqualArea ? bilinear_equal_area(uv.x, uv.y) : bilinear_latlong(uv.x, uv.y);
}

void EnvironmentMap::prefetch(Point2 uv) const {
  const auto fetch = [this](Point2 at) {
    const TexelCoord t = texel_coord(at);
    __builtin_prefetch(&pixels_[(static_cast<std::size_t>(t.y) * width_ + t.x) * 3]);
  };
  if (filter_ == MapFilter::Nearest) return fetch(uv);
  // A bilinear look-up reads the rows half a texel above and below uv (the texel beside lies on the
  // same or the next line).
  const float half = 0.5f / float(height_);
  fetch({uv.x, uv.y - half});
  fetch({uv.x, uv.y + half});
}

Point2 EnvironmentMap::texture_coord(Vec3 d) const {
  if (!is_valid_direction(d)) return {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::quiet_NaN()};
  const Vec3 m = to_map(d);
  return layout_ == MapLayout::EqualArea ? equal_area_sphere_to_square(m) : direction_to_latlong(m);
}

Rgb EnvironmentMap::eval(Vec3 d) const { return eval_texture(texture_coord(d)); }

}  // namespace envpis
