// SPDX-License-Identifier: Apache-2.0
// Portals (envpis/portals.h, envpis/portal_sampler.h; docs/portals.md): the quads, a view of them from
// one shading point, and environment-only sampling through them. ProductSampler.prepare takes the view
// too (bind_product_sampler.cpp).
#include <envpis/portal_sampler.h>
#include <envpis/portals.h>

#include <string>
#include <vector>

#include "arrays.h"
#include "module.h"

namespace envpis_py {

namespace {

using envpis::PortalEnvironmentSampler;
using envpis::Portals;
using envpis::PortalView;
using envpis::PortalViewOptions;
using envpis::Quad;

/// One quad (4 x 3 numbers) or N quads (N x 4 x 3): the vertices counter-clockwise seen from outside.
std::vector<Quad> quads(py::handle obj) {
  const FloatArray a = as_floats(obj, "quads");
  const bool one = a.ndim() == 2;
  if (!(one || a.ndim() == 3) || a.shape(a.ndim() - 2) != 4 || a.shape(a.ndim() - 1) != 3)
    throw py::value_error("quads: expected 4 x 3 numbers (one quad) or N x 4 x 3");
  const py::ssize_t n = one ? 1 : a.shape(0);
  std::vector<Quad> out(static_cast<std::size_t>(n));
  const float* v = a.data();
  for (py::ssize_t i = 0; i < n; ++i)
    for (int k = 0; k < 4; ++k, v += 3) out[static_cast<std::size_t>(i)].v[k] = {v[0], v[1], v[2]};
  return out;
}

}  // namespace

void bind_portals(py::module_& m) {
  py::class_<Portals>(m, "Portals",
                      "Up to 8 planar convex quads (windows), each 4 vertices counter-clockwise seen from the "
                      "environment; validated on entry (ValueError names the bad quad).")
      .def(py::init<>())
      .def(py::init([](py::handle q) { return Portals(quads(q)); }), py::arg("quads"))
      .def(
          "add", [](Portals& p, py::handle q) {
            for (const Quad& quad : quads(q)) p.add(quad);
          },
          py::arg("quad"), "Adds one quad (4 x 3) or several (N x 4 x 3).")
      .def("__len__", &Portals::size)
      .def(
          "quad",
          [](const Portals& p, int i) {
            if (i < 0 || i >= p.size()) throw py::index_error("portal index out of range");
            py::array_t<float> out({4, 3});
            float* o = out.mutable_data();
            for (int k = 0; k < 4; ++k, o += 3) o[0] = p.quad(i).v[k].x, o[1] = p.quad(i).v[k].y, o[2] = p.quad(i).v[k].z;
            return out;
          },
          py::arg("i"), "Quad i's vertices, 4 x 3.")
      .def(
          "normal",
          [](const Portals& p, int i) {
            if (i < 0 || i >= p.size()) throw py::index_error("portal index out of range");
            return vec3_array(p.normal(i));
          },
          py::arg("i"), "Quad i's unit normal, pointing out of the room.")
      .def(
          "passes",
          [](const Portals& p, py::handle point, py::handle dirs) {
            const envpis::Vec3 o = vec3(point, "p");
            return map_rows(dirs, "dirs", 3, 1, [&](const float* d, float* r) { *r = p.passes(o, {d[0], d[1], d[2]}); });
          },
          py::arg("p"), py::arg("dirs"),
          "Exact: 1 where the ray from p along each direction (N x 3, or 3 numbers) leaves through a portal.");

  const PortalViewOptions d;
  py::class_<PortalViewOptions>(m, "PortalViewOptions", "Options of PortalView (portals.h).")
      .def(py::init<>())
      .def_property(
          "estimate", [](const PortalViewOptions& o) { return std::string(envpis::to_string(o.estimate)); },
          [](PortalViewOptions& o, const std::string& s) { o.estimate = envpis::parse_portal_estimate(s); },
          "a partial cell's visible fraction: 'cone' (default) or 'grid'")
      .def_readwrite("grid", &PortalViewOptions::grid, "K for the 'grid' estimate, 1..16")
      .def_property(
          "simd", [](const PortalViewOptions& o) { return std::string(envpis::to_string(o.simd)); },
          [](PortalViewOptions& o, const std::string& s) { o.simd = envpis::parse_simd(s); },
          "instruction set of the top cells' pass: 'best' (default), 'scalar', 'sse2', 'avx2' or 'avx512'");

  py::class_<PortalView>(m, "PortalView",
                         "The portals seen from one shading point, per top cell of a table: prepare(p), then "
                         "hand it to PortalEnvironmentSampler.prepare or ProductSampler.prepare. Keeps its "
                         "table alive.")
      .def(py::init<const envpis::ImportanceTable&, const Portals&, const PortalViewOptions&>(), py::arg("table"),
           py::arg("portals"), py::arg("options") = d, py::keep_alive<1, 2>())
      .def(
          "prepare", [](PortalView& v, py::handle p) { return v.prepare(vec3(p, "p")); }, py::arg("p"),
          "Estimates each cell's visible fraction from point p. Returns visible: False when p is not finite "
          "or sees no portal.")
      .def_property_readonly("visible", &PortalView::visible)
      .def("cell_fractions",
           [](const PortalView& v) {
             return top_grid(v.table().top_resolution(), v.visible(), [&](int c) { return v.cell_fraction(c); });
           },
           "Each top cell's estimated visible fraction, T x T in [0, 1] (zeros when not visible).")
      .def(
          "passes",
          [](const PortalView& v, py::handle dirs) {
            return map_rows(dirs, "dirs", 3, 1, [&](const float* d, float* r) { *r = v.passes({d[0], d[1], d[2]}); });
          },
          py::arg("dirs"), "Exact, from the prepared point: 1 where a direction leaves through a portal.");

  py::class_<PortalEnvironmentSampler>(m, "PortalEnvironmentSampler",
                                       "Environment-only sampling through portals: prepare(view), then sample() "
                                       "/ pdf(). Keeps its table and the last prepared view alive.")
      .def(py::init<const envpis::ImportanceTable&>(), py::arg("table"), py::keep_alive<1, 2>())
      .def("prepare", &PortalEnvironmentSampler::prepare, py::arg("view"), py::keep_alive<1, 2>(),
           "Weighs the cells by environment x visible fraction for the view's point. Returns valid.")
      .def("sample", [](const PortalEnvironmentSampler& s, py::handle u) { return sample_rows(u, [&](envpis::Point2 p) { return s.sample(p); }); },
           py::arg("u"), "u (N x 2 in [0,1), or 2 numbers) -> (directions N x 3, pdfs N); pdf 0 means no sample.")
      .def(
          "pdf",
          [](const PortalEnvironmentSampler& s, py::handle dirs) {
            return map_rows(dirs, "dirs", 3, 1, [&s](const float* v, float* p) { *p = s.pdf({v[0], v[1], v[2]}); });
          },
          py::arg("dirs"), "Density (solid angle) of sample() at directions (N x 3, or 3 numbers); 0 where no portal is.")
      .def("cell_probabilities",
           [](const PortalEnvironmentSampler& s) {
             return top_grid(s.table().top_resolution(), s.valid(), [&](int c) { return s.cell_probability(c); });
           },
           "The prepared top-level distribution, T x T (zeros when not valid).")
      .def_property_readonly("valid", &PortalEnvironmentSampler::valid);
}

}  // namespace envpis_py
