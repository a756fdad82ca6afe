// SPDX-License-Identifier: Apache-2.0
// The renderer's camera, built from look-at parameters (+Z is the world's up by default): a pinhole
// perspective camera, or an orthographic one whose primary rays are all parallel to the view
// direction. The orthographic camera shows sizes without perspective (technical and product views,
// a light probe seen from afar) and makes every primary ray look up the same environment direction.
#pragma once

#include <cmath>

#include "envpis/common.h"
#include "render/math.h"

namespace envpis::render {

enum class Projection {
  Perspective,   ///< rays from `from` through the film, vertical field of view `vfov_degrees`
  Orthographic,  ///< parallel rays from a film of height `ortho_height` centred on `from`
};

struct CameraSpec {
  Vec3 from{0, -10, 0};
  Vec3 to{0, 0, 0};
  Vec3 up{0, 0, 1};
  Projection projection = Projection::Perspective;
  float vfov_degrees = 40.0f;  ///< perspective: full vertical field of view
  float ortho_height = 0.0f;   ///< orthographic: the film's height in world units (its width: height * aspect)
  int width = 640;             ///< default image size (the render options may override it)
  int height = 360;
};

/// A perspective camera at `from` looking at `to`, +Z up.
inline CameraSpec look_at(Vec3 from, Vec3 to, float vfov_degrees, int width, int height) {
  CameraSpec c;
  c.from = from;
  c.to = to;
  c.vfov_degrees = vfov_degrees;
  c.width = width;
  c.height = height;
  return c;
}

class Camera {
 public:
  Camera() = default;
  /// Throws envpis::Error for a degenerate specification (from == to, up parallel to the view
  /// direction, perspective fov outside (0, 180), orthographic film height not positive and finite).
  Camera(const CameraSpec& spec, int width, int height) : width_(width), height_(height) {
    const Vec3 d = spec.to - spec.from;
    if (!is_valid_direction(d)) throw Error("camera: 'from' and 'to' must differ");
    if (spec.projection == Projection::Perspective && !(spec.vfov_degrees > 0 && spec.vfov_degrees < 180))
      throw Error("camera: fov must be in (0, 180) degrees");
    if (spec.projection == Projection::Orthographic && !(spec.ortho_height > 0 && std::isfinite(spec.ortho_height)))
      throw Error("camera: ortho_height must be a positive finite number");
    if (!is_valid_direction(spec.up)) throw Error("camera: 'up' must be a non-zero vector");
    if (width <= 0 || height <= 0) throw Error("camera: image size must be positive");
    origin_ = spec.from;
    forward_ = normalize(d);
    const Vec3 r = cross(forward_, normalize(spec.up));
    if (!(length(r) > 1e-6f)) throw Error("camera: 'up' is parallel to the view direction");
    right_ = normalize(r);
    up_ = cross(right_, forward_);
    orthographic_ = spec.projection == Projection::Orthographic;
    // Half the film's height: at unit distance for the pinhole, in world units for the orthographic film.
    half_height_ = orthographic_ ? 0.5f * spec.ortho_height : std::tan(0.5f * spec.vfov_degrees * kPi / 180.0f);
    aspect_ = float(width) / float(height);
  }

  /// Primary ray through film position (fx, fy) in pixels: (0, 0) is the top-left corner of the
  /// image, (width, height) the bottom-right one.
  Ray generate_ray(float fx, float fy) const {
    const float sx = (2.0f * fx / float(width_) - 1.0f) * half_height_ * aspect_;
    const float sy = (1.0f - 2.0f * fy / float(height_)) * half_height_;
    if (orthographic_) return {origin_ + right_ * sx + up_ * sy, forward_, kInfinity};
    return {origin_, normalize(forward_ + right_ * sx + up_ * sy), kInfinity};
  }

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_ = 1, height_ = 1;
  Vec3 origin_, forward_{0, 1, 0}, right_{1, 0, 0}, up_{0, 0, 1};
  bool orthographic_ = false;
  float half_height_ = 1, aspect_ = 1;
};

}  // namespace envpis::render
