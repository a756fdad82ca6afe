// SPDX-License-Identifier: Apache-2.0
// Clarberg's equal-area mapping on arrays of points / directions.
#include <envpis/equal_area.h>

#include "arrays.h"
#include "module.h"

namespace envpis_py {

void bind_equal_area(py::module_& m) {
  m.def(
      "equal_area_square_to_sphere",
      [](py::handle uv) {
        return map_rows(uv, "uv", 2, 3, [](const float* p, float* d) {
          const envpis::Vec3 v = envpis::equal_area_square_to_sphere({p[0], p[1]});
          d[0] = v.x, d[1] = v.y, d[2] = v.z;
        });
      },
      py::arg("uv"),
      "Points of the unit square (N x 2, or 2 numbers; clamped to [0,1]) -> unit directions (N x 3).");
  m.def(
      "equal_area_sphere_to_square",
      [](py::handle dirs) {
        return map_rows(dirs, "dirs", 3, 2, [](const float* d, float* p) {
          const envpis::Point2 q = envpis::equal_area_sphere_to_square({d[0], d[1], d[2]});
          p[0] = q.x, p[1] = q.y;
        });
      },
      py::arg("dirs"),
      "Directions (N x 3, or 3 numbers; need not be unit, must be non-zero) -> points of the unit "
      "square (N x 2).");
  m.attr("EQUAL_AREA_PDF") = envpis::kEqualAreaPdf;
}

}  // namespace envpis_py
