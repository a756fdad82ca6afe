// SPDX-License-Identifier: Apache-2.0
#include "proxy_rows.h"

#include <string>

namespace envpis_py {

const char* const kProxyFields[kProxyFloats] = {"diffuse",          "translucent",      "reflection", "refraction",
                                                "alpha_reflection", "alpha_refraction", "ior"};

py::array_t<float> proxy_array(const envpis::BsdfProxy& p) {
  py::array_t<float> out(kProxyFloats);
  proxy_to_row(p, out.mutable_data());
  return out;
}

namespace {

// A structured array: its named fields, stacked as columns (numpy does the field access and the
// conversion, so any numeric field types work).
py::array_t<float> from_fields(const py::array& a) {
  const py::object names = a.dtype().attr("names");
  if (a.ndim() != 1) throw py::value_error("proxies: a structured array must be one-dimensional");
  py::array_t<float> out({a.shape(0), kProxyFloats});
  auto o = out.mutable_unchecked<2>();
  for (int f = 0; f < kProxyFloats; ++f) {
    if (!names.contains(kProxyFields[f]))
      throw py::value_error(std::string("proxies: the structured array has no field '") + kProxyFields[f] + "'");
    const FloatArray column = as_floats(a[py::str(kProxyFields[f])], kProxyFields[f]);
    const float* c = column.data();
    for (py::ssize_t i = 0; i < a.shape(0); ++i) o(i, f) = c[i];
  }
  return out;
}

// A list or tuple whose items are all BsdfProxy; an empty handle otherwise.
py::object from_proxy_list(py::handle obj) {
  if (!py::isinstance<py::list>(obj) && !py::isinstance<py::tuple>(obj)) return {};
  const py::sequence seq = py::reinterpret_borrow<py::sequence>(obj);
  if (seq.size() == 0 || !py::isinstance<envpis::BsdfProxy>(seq[0])) return {};
  py::array_t<float> out({static_cast<py::ssize_t>(seq.size()), kProxyFloats});
  float* o = out.mutable_data();
  for (std::size_t i = 0; i < seq.size(); ++i) {
    if (!py::isinstance<envpis::BsdfProxy>(seq[i]))
      throw py::value_error("proxies: item " + std::to_string(i) + " of the list is not a BsdfProxy");
    proxy_to_row(seq[i].cast<envpis::BsdfProxy>(), o + i * kProxyFloats);
  }
  return std::move(out);
}

}  // namespace

RowInput proxy_rows(py::handle obj) {
  if (py::isinstance<envpis::BsdfProxy>(obj)) return row_input(proxy_array(obj.cast<envpis::BsdfProxy>()), "proxies", kProxyFloats);
  if (py::object list = from_proxy_list(obj)) return row_input(list, "proxies", kProxyFloats);
  if (py::isinstance<py::array>(obj)) {
    const py::array a = py::reinterpret_borrow<py::array>(obj);
    if (py::hasattr(a.dtype(), "names") && !a.dtype().attr("names").is_none())
      return row_input(from_fields(a), "proxies", kProxyFloats);
  }
  return row_input(obj, "proxies", kProxyFloats);
}

envpis::BsdfProxy one_proxy(py::handle obj) {
  const RowInput p = proxy_rows(obj);
  if (p.count != 1) throw py::value_error("proxy must be one BsdfProxy or 7 numbers");
  return proxy_from_row(p.row(0));
}

}  // namespace envpis_py
