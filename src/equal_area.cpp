// SPDX-License-Identifier: Apache-2.0
#include "envpis/equal_area.h"

#define ENVPIS_KERNEL_NS scalar
#include "kernels_impl.inl"

namespace envpis {

namespace detail {
const Kernels& kernels_scalar() {
  static const Kernels k = scalar::make_kernels<float>("scalar");
  return k;
}
}  // namespace detail

Vec3 equal_area_square_to_sphere(Point2 p) {
  Vec3 d;
  detail::scalar::square_to_sphere_one<float>(p.x, p.y, d.x, d.y, d.z);
  return d;
}

Point2 equal_area_sphere_to_square(Vec3 d) {
  Point2 p;
  detail::scalar::sphere_to_square_one<float>(d.x, d.y, d.z, p.x, p.y);
  return p;
}

bool equal_area_wrap(int n, int& x, int& y) {
  if (x < -n || x >= 2 * n || y < -n || y >= 2 * n) return false;
  if (x < 0) {
    x = -x - 1;
    y = n - 1 - y;
  } else if (x >= n) {
    x = 2 * n - 1 - x;
    y = n - 1 - y;
  }
  if (y < 0) {
    y = -y - 1;
    x = n - 1 - x;
  } else if (y >= n) {
    y = 2 * n - 1 - y;
    x = n - 1 - x;
  }
  return x >= 0 && x < n && y >= 0 && y < n;
}

void equal_area_square_to_sphere(std::size_t n, const float* u, const float* v, float* x, float* y, float* z,
                                 Simd simd) {
  detail::kernels_for(simd).square_to_sphere(n, u, v, x, y, z);
}

void equal_area_sphere_to_square(std::size_t n, const float* x, const float* y, const float* z, float* u, float* v,
                                 Simd simd) {
  detail::kernels_for(simd).sphere_to_square(n, x, y, z, u, v);
}

}  // namespace envpis
