// SPDX-License-Identifier: Apache-2.0
// ImportanceTable: the two-level table, environment-only sampling and pdf on arrays, and its
// importance and cell probabilities as arrays (for plots).
#include <envpis/importance_table.h>

#include <string>

#include "arrays.h"
#include "module.h"

namespace envpis_py {

namespace {

using envpis::ImportanceTable;
using envpis::ImportanceTableOptions;

ImportanceTable make_table(const envpis::EnvironmentMap& map, int top_resolution, int fine_resolution,
                           float floor, float peak_ratio, bool compensated, int subdivision,
                           const std::string& fine_texels) {
  ImportanceTableOptions o;
  o.fine_texels = envpis::parse_fine_texels(fine_texels);
  o.top_resolution = top_resolution;
  o.subdivision = subdivision;
  o.fine_resolution = fine_resolution;
  o.floor = floor;
  o.peak_ratio = peak_ratio;
  o.compensated = compensated;
  py::gil_scoped_release release;  // the build runs on TBB's threads
  return ImportanceTable(map, o);
}

py::array_t<float> importance(const ImportanceTable& t) {
  const int w = t.importance_width(), h = t.importance_height();
  py::array_t<float> out({h, w});
  float* o = out.mutable_data();
  py::gil_scoped_release release;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) o[static_cast<std::size_t>(y) * w + x] = t.importance(x, y);
  return out;
}

py::array_t<float> cell_probabilities(const ImportanceTable& t) {
  return top_grid(t.top_resolution(), true, [&](int c) { return t.cell_probability(c); });
}

}  // namespace

void bind_importance_table(py::module_& m) {
  const ImportanceTableOptions d;
  py::class_<ImportanceTable>(m, "ImportanceTable",
                              "The two-level importance table of a map on the equal-area square "
                              "(T x T top cells, N x N fine texels). Immutable; safe to share.")
      .def(py::init(&make_table), py::arg("map"), py::arg("top_resolution") = d.top_resolution,
           py::arg("fine_resolution") = d.fine_resolution, py::arg("floor") = d.floor,
           py::arg("peak_ratio") = d.peak_ratio, py::arg("compensated") = d.compensated,
           py::arg("subdivision") = d.subdivision, py::arg("fine_texels") = envpis::to_string(d.fine_texels),
           "fine_resolution 0: derived from the map's texel count; subdivision: S x S sub-cells per top "
           "cell (a refined ProductSampler needs S > 1); fine_texels: 'equal-area', 'map' (a lat-long "
           "map's own texels) or 'auto'. envpis.Error for invalid options.")
      .def(
          "sample",
          [](const ImportanceTable& t, py::handle u) {
            return sample_rows(u, [&](envpis::Point2 p) { return t.sample(p); });
          },
          py::arg("u"),
          "Environment-only sampling: u (N x 2 in [0,1)) -> (directions N x 3, pdfs N, per solid "
          "angle; 0 means no sample).")
      .def(
          "pdf",
          [](const ImportanceTable& t, py::handle dirs) {
            return map_rows(dirs, "dirs", 3, 1, [&t](const float* d, float* p) { *p = t.pdf({d[0], d[1], d[2]}); });
          },
          py::arg("dirs"), "Density (solid angle) of sample() at directions (N x 3) -> N.")
      .def("importance", &importance,
           "Fine texel importance: N x N on the equal-area square (row = y), or the map's height x width "
           "for fine_texels 'map'.")
      .def_property_readonly("fine_texels",
                             [](const ImportanceTable& t) { return std::string(envpis::to_string(t.fine_texels())); })
      .def("cell_probabilities", &cell_probabilities, "Top cell probabilities E[c], T x T (sum 1).")
      .def_property_readonly("top_resolution", &ImportanceTable::top_resolution)
      .def_property_readonly("fine_resolution", &ImportanceTable::fine_resolution)
      .def_property_readonly("cell_resolution", &ImportanceTable::cell_resolution)
      .def_property_readonly("subdivision", &ImportanceTable::subdivision)
      .def_property_readonly("cell_count", &ImportanceTable::cell_count)
      .def_property_readonly("empty", &ImportanceTable::empty)
      .def_property_readonly("integral", &ImportanceTable::integral)
      .def_property_readonly("bytes_used", &ImportanceTable::bytes_used)
      .def("__repr__", [](const ImportanceTable& t) {
        return "<envpis.ImportanceTable T=" + std::to_string(t.top_resolution()) +
               " N=" + std::to_string(t.fine_resolution()) + ">";
      });
}

}  // namespace envpis_py
