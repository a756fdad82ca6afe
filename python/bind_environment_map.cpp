// SPDX-License-Identifier: Apache-2.0
// EnvironmentMap: loaded from a file or built from an H x W x 3 array, evaluated on arrays of directions.
#include <envpis/environment_map.h>

#include <pybind11/stl.h>

#include <vector>

#include "arrays.h"
#include "module.h"

namespace envpis_py {

namespace {

using envpis::EnvironmentMap;
using envpis::EnvironmentMapOptions;

// The keyword options load() and from_array() share; strings are parsed by the library, so they
// and their error messages are the command line's ("latlong", "equal-area", ...).
EnvironmentMapOptions map_options(const std::string& layout, float scale, py::handle rotation,
                                  const std::string& orientation, const std::string& filter) {
  EnvironmentMapOptions o;
  o.layout = envpis::parse_map_layout(layout);
  o.scale = scale;
  o.orientation = envpis::parse_latlong_orientation(orientation);
  o.filter = envpis::parse_map_filter(filter);
  if (!rotation.is_none()) {
    const FloatArray r = rows(rotation, "rotation", 3);
    if (r.shape(0) != 3) throw py::value_error("rotation must be a 3 x 3 matrix");
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) o.rotation.m[i][j] = r.at(i, j);
  }
  return o;
}

EnvironmentMap from_array(py::handle pixels, const std::string& layout, float scale, py::handle rotation,
                          const std::string& orientation, const std::string& filter) {
  const FloatArray a = as_floats(pixels, "pixels");
  if (a.ndim() != 3 || a.shape(2) != 3 || a.shape(0) < 1 || a.shape(1) < 1)
    throw py::value_error("pixels must have shape (height, width, 3) with height, width >= 1");
  if (a.shape(0) > (1 << 16) || a.shape(1) > (1 << 16))
    throw py::value_error("pixels: height and width must be at most 65536");
  std::vector<float> rgb(a.data(), a.data() + a.size());
  return EnvironmentMap::from_pixels(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), std::move(rgb),
                                     map_options(layout, scale, rotation, orientation, filter));
}

py::array_t<float> texels(const EnvironmentMap& map) {
  py::array_t<float> out({map.height(), map.width(), 3});
  auto o = out.mutable_unchecked<3>();
  for (int y = 0; y < map.height(); ++y)
    for (int x = 0; x < map.width(); ++x) {
      const envpis::Rgb c = map.texel(x, y);
      o(y, x, 0) = c.r, o(y, x, 1) = c.g, o(y, x, 2) = c.b;
    }
  return out;
}

}  // namespace

void bind_environment_map(py::module_& m) {
  py::class_<EnvironmentMap>(m, "EnvironmentMap",
                             "An HDR environment map (linear RGB radiance over the sphere, +Z up).\n"
                             "layout: 'auto' (square -> equal-area), 'latlong' or 'equal-area'; "
                             "orientation: 'panorama' (Blender) or 'legacy'; filter: 'bilinear' or 'nearest'; "
                             "rotation: 3 x 3 (world = rotation * map direction).")
      .def_static(
          "load",
          [](const std::string& path, const std::string& layout, float scale, py::handle rotation,
             const std::string& orientation, const std::string& filter) {
            const EnvironmentMapOptions o = map_options(layout, scale, rotation, orientation, filter);
            py::gil_scoped_release release;
            return EnvironmentMap::load(path, o);
          },
          py::arg("path"), py::arg("layout") = "auto", py::arg("scale") = 1.0f, py::arg("rotation") = py::none(),
          py::arg("orientation") = "panorama", py::arg("filter") = "bilinear",
          "Loads an OpenEXR, PNG, Radiance HDR or other OpenImageIO image; envpis.Error names the file and "
          "the reason when it cannot.")
      .def_static("from_array", &from_array, py::arg("pixels"), py::arg("layout") = "auto",
                  py::arg("scale") = 1.0f, py::arg("rotation") = py::none(), py::arg("orientation") = "panorama",
                  py::arg("filter") = "bilinear",
                  "Builds a map from an H x W x 3 array of linear RGB (top row first). NaN, infinite "
                  "and negative values are repaired to 0, as load() does.")
      .def(
          "eval",
          [](const EnvironmentMap& map, py::handle dirs) {
            return map_rows(dirs, "dirs", 3, 3, [&map](const float* d, float* rgb) {
              const envpis::Rgb c = map.eval({d[0], d[1], d[2]});
              rgb[0] = c.r, rgb[1] = c.g, rgb[2] = c.b;
            });
          },
          py::arg("dirs"), "Radiance (N x 3 RGB) arriving from directions (N x 3); 0 for invalid ones.")
      .def("to_array", &texels, "The texels after repair and scale, H x W x 3.")
      .def_property_readonly("width", &EnvironmentMap::width)
      .def_property_readonly("height", &EnvironmentMap::height)
      .def_property_readonly("layout", [](const EnvironmentMap& m) { return envpis::to_string(m.layout()); })
      .def_property_readonly("orientation",
                             [](const EnvironmentMap& m) { return envpis::to_string(m.orientation()); })
      .def_property_readonly("filter", [](const EnvironmentMap& m) { return envpis::to_string(m.filter()); })
      .def_property_readonly("scale", &EnvironmentMap::scale)
      .def_property_readonly("path", &EnvironmentMap::path)
      .def_property_readonly("max_radiance", &EnvironmentMap::max_radiance)
      .def_property_readonly("is_black", &EnvironmentMap::is_black)
      .def("warnings", &EnvironmentMap::warnings, "One-line warnings about the map (repaired texels, ...).")
      .def("__repr__", [](const EnvironmentMap& m) {
        return "<envpis.EnvironmentMap " + std::to_string(m.width()) + "x" + std::to_string(m.height()) + " " +
               envpis::to_string(m.layout()) + (m.path().empty() ? "" : " '" + m.path() + "'") + ">";
      });
}

}  // namespace envpis_py
