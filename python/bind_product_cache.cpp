// SPDX-License-Identifier: Apache-2.0
// ProductCache and its options (product_cache.h): product distributions shared by the shading points
// that round to the same normal, view and proxy.
#include <envpis/product_cache.h>

#include "arrays.h"
#include "module.h"
#include "proxy_rows.h"

namespace envpis_py {

namespace {

using envpis::ProductCache;
using envpis::ProductCacheOptions;

py::tuple rounded(const ProductCache& c, py::handle n, py::handle wo, py::handle proxy) {
  const ProductCache::Rounded r = c.round(vec3(n, "normal"), vec3(wo, "wo"), one_proxy(proxy));
  return py::make_tuple(vec3_array(r.n), vec3_array(r.wo), r.proxy);
}

}  // namespace

void bind_product_cache(py::module_& m) {
  const ProductCacheOptions d;
  py::class_<ProductCacheOptions>(m, "ProductCacheOptions", "Options of the product cache (product_cache.h).")
      .def(py::init<>())
      .def_readwrite("resolution", &ProductCacheOptions::resolution,
                     "K: the normal's and wo's components are rounded to multiples of 1/K, 1..4095")
      .def_readwrite("entries", &ProductCacheOptions::entries, "prepared samplers kept, 1..1024");

  py::class_<ProductCache>(m, "ProductCache",
                           "Prepared ProductSamplers shared by the shading points whose normal, wo and proxy "
                           "round to the same key: the distribution at a point is a function of its key alone "
                           "(that of the point round() returns), whatever the cache's size or history.")
      .def(py::init<const envpis::ImportanceTable&, const envpis::ProductSamplerOptions&, const ProductCacheOptions&>(),
           py::arg("table"), py::arg("sampler") = envpis::ProductSamplerOptions{}, py::arg("options") = d,
           py::keep_alive<1, 2>())
      .def(
          "prepare",
          [](ProductCache& c, py::handle n, py::handle wo, py::handle proxy) -> const envpis::ProductSampler& {
            return c.prepare(vec3(n, "normal"), vec3(wo, "wo"), one_proxy(proxy));
          },
          py::arg("normal"), py::arg("wo"), py::arg("proxy"), py::return_value_policy::reference_internal,
          "The sampler prepared for the point's key. It belongs to the cache: the next prepare() may "
          "prepare it again for another point, so use it before calling prepare() again.")
      .def("round", &rounded, py::arg("normal"), py::arg("wo"), py::arg("proxy"),
           "(normal, wo, BsdfProxy): the rounded point prepare() prepares for.")
      .def_property_readonly("hits", &ProductCache::hits, "prepare() calls that reused a prepared sampler")
      .def_property_readonly("misses", &ProductCache::misses, "prepare() calls that prepared one")
      .def_property_readonly("options", &ProductCache::options);
}

}  // namespace envpis_py
