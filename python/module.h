// SPDX-License-Identifier: Apache-2.0
// The envpis Python module is assembled from one binding file per library concept.
#pragma once

#include <pybind11/pybind11.h>

namespace envpis_py {

namespace py = pybind11;

void bind_equal_area(py::module_& m);
void bind_environment_map(py::module_& m);
void bind_importance_table(py::module_& m);
void bind_bsdf_proxy(py::module_& m);
void bind_product_sampler(py::module_& m);
void bind_product_cache(py::module_& m);
void bind_portals(py::module_& m);
void bind_batch(py::module_& m);

}  // namespace envpis_py
