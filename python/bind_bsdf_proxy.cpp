// SPDX-License-Identifier: Apache-2.0
// BsdfProxy (the seven floats and their add_* accumulation) and ProxyOptions.
#include <envpis/bsdf_proxy.h>

#include "module.h"
#include "proxy_rows.h"

namespace envpis_py {

namespace {

using envpis::BsdfProxy;
using envpis::ProxyOptions;

BsdfProxy proxy_from_array(py::handle values) {
  bool single = false;
  const FloatArray a = rows(values, "values", kProxyFloats, true, &single);
  if (!single && a.shape(0) != 1) throw py::value_error("values must be 7 numbers");
  return proxy_from_row(a.data());
}

}  // namespace

void bind_bsdf_proxy(py::module_& m) {
  py::class_<BsdfProxy>(m, "BsdfProxy",
                        "The seven-float summary of a BSDF that shapes light sampling. Accumulate lobes "
                        "with the add_* calls (weights: the lobes' albedos; roughness: GGX alpha). As a "
                        "row of a batched call's proxies array its fields are, in order, PROXY_FIELDS.")
      .def(py::init<>())
      .def_static("from_array", &proxy_from_array, py::arg("values"), "A proxy from 7 numbers (PROXY_FIELDS order).")
      .def("to_array", &proxy_array, "The 7 fields as a float32 array (PROXY_FIELDS order).")
      .def("add_diffuse", &BsdfProxy::add_diffuse, py::arg("weight"))
      .def("add_translucent", &BsdfProxy::add_translucent, py::arg("weight"))
      .def("add_reflection", &BsdfProxy::add_reflection, py::arg("weight"), py::arg("alpha"))
      .def("add_refraction", &BsdfProxy::add_refraction, py::arg("weight"), py::arg("alpha"), py::arg("ior"))
      .def_readwrite("diffuse", &BsdfProxy::diffuse)
      .def_readwrite("translucent", &BsdfProxy::translucent)
      .def_readwrite("reflection", &BsdfProxy::reflection)
      .def_readwrite("refraction", &BsdfProxy::refraction)
      .def_readwrite("alpha_reflection", &BsdfProxy::alpha_reflection)
      .def_readwrite("alpha_refraction", &BsdfProxy::alpha_refraction)
      .def_readwrite("ior", &BsdfProxy::ior)
      .def_property_readonly("is_zero", &BsdfProxy::is_zero)
      .def("__repr__", [](const BsdfProxy& p) {
        return py::str("BsdfProxy(diffuse={}, translucent={}, reflection={}, refraction={}, "
                       "alpha_reflection={}, alpha_refraction={}, ior={})")
            .format(p.diffuse, p.translucent, p.reflection, p.refraction, p.alpha_reflection,
                    p.alpha_refraction, p.ior);
      });

  py::tuple fields(kProxyFloats);
  for (int i = 0; i < kProxyFloats; ++i) fields[i] = kProxyFields[i];
  m.attr("PROXY_FIELDS") = fields;

  py::class_<ProxyOptions>(m, "ProxyOptions", "How a proxy becomes lobes at a shading point (bsdf_proxy.h).")
      .def(py::init<>())
      .def_property(
          "transform", [](const ProxyOptions& o) { return envpis::to_string(o.transform); },
          [](ProxyOptions& o, const std::string& s) { o.transform = envpis::parse_roughness_transform(s); },
          "roughness transform: 'hybrid' (default), 'slides', 'abstract' or 'fitted'")
      .def_property(
          "reflection_lobe", [](const ProxyOptions& o) { return envpis::to_string(o.reflection_lobe); },
          [](ProxyOptions& o, const std::string& s) { o.reflection_lobe = envpis::parse_reflection_lobe(s); },
          "reflection lobe: 'mirror' (default) or 'half-vector' (docs/proxy.md)")
      .def_readwrite("min_alpha", &ProxyOptions::min_alpha, "floor on the transformed roughness (0 disables)")
      .def_readwrite("max_alpha", &ProxyOptions::max_alpha, "cap on the transformed roughness (1 disables)");
}

}  // namespace envpis_py
