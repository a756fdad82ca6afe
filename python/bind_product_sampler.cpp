// SPDX-License-Identifier: Apache-2.0
// ProductSampler and its options: the per-shading-point API (prepare once, then sample / pdf on
// arrays). The batched calls over many shading points are in batch.cpp.
#include <envpis/portals.h>
#include <envpis/product_sampler.h>

#include "module.h"
#include "proxy_rows.h"

namespace envpis_py {

namespace {

using envpis::ProductSampler;
using envpis::ProductSamplerOptions;

bool prepare(ProductSampler& s, py::handle n, py::handle wo, py::handle proxy, const envpis::PortalView* view) {
  return s.prepare(vec3(n, "normal"), vec3(wo, "wo"), one_proxy(proxy), view);
}

py::tuple sample(const ProductSampler& s, py::handle u) {
  return sample_rows(u, [&](envpis::Point2 p) { return s.sample(p); });
}

py::array_t<float> cell_probabilities(const ProductSampler& s) {
  return top_grid(s.table().top_resolution(), s.valid(), [&](int c) { return s.cell_probability(c); });
}

}  // namespace

void bind_product_sampler(py::module_& m) {
  const ProductSamplerOptions d;
  py::class_<ProductSamplerOptions>(m, "ProductSamplerOptions", "Options of the product sampler (product_sampler.h).")
      .def(py::init<>())
      .def_readwrite("proxy", &ProductSamplerOptions::proxy)
      .def_readwrite("env_mix", &ProductSamplerOptions::env_mix,
                     "fraction of the environment-only distribution mixed in, [0, 1]")
      .def_readwrite("env_floor", &ProductSamplerOptions::env_floor,
                     "every cell the proxy sees keeps at least this times its environment share, [0, 1]")
      .def_readwrite("refine", &ProductSamplerOptions::refine,
                     "choose the sub-cell by the product too (needs a table with subdivision > 1)")
      .def_readwrite("refine_cells", &ProductSamplerOptions::refine_cells,
                     "with refine: the heaviest top cells re-weighed from their sub-cells in prepare(), 0..64")
      .def_property(
          "cell_estimate",
          [](const ProductSamplerOptions& o) { return std::string(envpis::to_string(o.cell_estimate)); },
          [](ProductSamplerOptions& o, const std::string& name) { o.cell_estimate = envpis::parse_cell_estimate(name); },
          "how a cell's proxy value is estimated: 'cone' (default, the paper's) or 'moments' (at the cell's "
          "importance-weighted mean direction)")
      .def_property(
          "simd", [](const ProductSamplerOptions& o) { return std::string(envpis::to_string(o.simd)); },
          [](ProductSamplerOptions& o, const std::string& name) { o.simd = envpis::parse_simd(name); },
          "instruction set of the weights kernel: 'best' (default), 'scalar', 'sse2', 'avx2' or 'avx512'");

  py::class_<ProductSampler>(m, "ProductSampler",
                             "Product (environment x BSDF proxy) sampling at one shading point: prepare(), "
                             "then sample() / pdf() any number of times. Keeps its table alive.")
      .def(py::init<const envpis::ImportanceTable&, const ProductSamplerOptions&>(), py::arg("table"),
           py::arg("options") = d, py::keep_alive<1, 2>())
      .def("prepare", &prepare, py::arg("normal"), py::arg("wo"), py::arg("proxy"), py::arg("view") = nullptr,
           py::keep_alive<1, 5>(),
           "Builds the product distribution for a shading point (normal, outgoing direction wo, proxy: "
           "a BsdfProxy or 7 numbers; view: a PortalView prepared for the point, or None). Returns valid: "
           "False for a zero/NaN normal or wo, an empty table, or a view that sees no portal.")
      .def("sample", &sample, py::arg("u"),
           "u (N x 2 in [0,1), or 2 numbers) -> (directions N x 3, pdfs N); pdf 0 means no sample.")
      .def(
          "pdf",
          [](const ProductSampler& s, py::handle dirs) {
            return map_rows(dirs, "dirs", 3, 1, [&s](const float* v, float* p) { *p = s.pdf({v[0], v[1], v[2]}); });
          },
          py::arg("dirs"), "Density (solid angle) of sample() at directions (N x 3, or 3 numbers).")
      .def("cell_probabilities", &cell_probabilities,
           "The prepared top-level distribution, T x T (sums to 1; zeros when not valid).")
      .def_property_readonly("valid", &ProductSampler::valid)
      .def_property_readonly("refines", &ProductSampler::refines)
      .def_property_readonly("uses_environment_fallback", &ProductSampler::uses_environment_fallback)
      .def_property_readonly("options", &ProductSampler::options);
}

}  // namespace envpis_py
