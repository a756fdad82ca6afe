// SPDX-License-Identifier: Apache-2.0
// envpis: small value types shared by every part of the library.
// The library uses its own minimal vector types so that it depends on no renderer's math library;
// converting from yours is three floats.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace envpis {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.318309886183790671538f;
constexpr float kInv4Pi = 0.0795774715459476678844f;

/// Every error the library reports (unreadable file, invalid option, ...). what() names the cause.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr Vec3 operator+(Vec3 o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(Vec3 o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
constexpr Vec3 operator*(float s, Vec3 v) { return v * s; }
constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(Vec3 v) { return v * (1.0f / length(v)); }
/// True when all components are finite and the vector is not (nearly) zero.
inline bool is_valid_direction(Vec3 v) {
  const float l2 = dot(v, v);
  return std::isfinite(l2) && l2 > 1e-20f;
}

struct Point2 {
  float x = 0, y = 0;
};

struct Rgb {
  float r = 0, g = 0, b = 0;
  constexpr Rgb operator+(Rgb o) const { return {r + o.r, g + o.g, b + o.b}; }
  constexpr Rgb operator*(float s) const { return {r * s, g * s, b * s}; }
  constexpr Rgb operator*(Rgb o) const { return {r * o.r, g * o.g, b * o.b}; }
  constexpr float average() const { return (r + g + b) * (1.0f / 3.0f); }
};

/// A sampled direction: pdf is per unit solid angle; pdf == 0 means "no sample" (ignore it).
struct DirectionSample {
  Vec3 direction;
  float pdf = 0;
  int cell = -1;  ///< top-level cell the sample came from (row-major, y * T + x), -1 if none
  /// Where `direction` reads the environment map the sampler's table was built from
  /// (EnvironmentMap::texture_coord), when sampling computed it anyway (tables on the map's own
  /// texels do); NaN otherwise. eval_texture(texture) is then eval(direction), without a second look-up.
  Point2 texture{std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::quiet_NaN()};
};

/// A row-major 3x3 rotation (world = m * local).
struct Mat3 {
  float m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 operator*(Vec3 v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  Mat3 transposed() const {
    Mat3 t;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) t.m[i][j] = m[j][i];
    return t;
  }
  /// Rotation by `degrees` about the +Z (up) axis.
  static Mat3 rotate_z(float degrees) {
    const float a = degrees * (kPi / 180.0f), c = std::cos(a), s = std::sin(a);
    Mat3 r;
    r.m[0][0] = c; r.m[0][1] = -s; r.m[1][0] = s; r.m[1][1] = c;
    return r;
  }
};

}  // namespace envpis
