// SPDX-License-Identifier: Apache-2.0
// The module entry point: library errors become envpis.Error (a RuntimeError) with the library's
// message; argument errors are ValueError (raised by the binding files).
#include <envpis/common.h>
#include <envpis/equal_area.h>
#include <envpis/version.h>

#include "module.h"

PYBIND11_MODULE(envpis, m) {
  namespace py = pybind11;
  m.doc() =
      "envpis: product importance sampling of environment maps (Conty Estevez & Lecocq 2018).\n"
      "Arrays are float32 (other numbers are converted); directions are rows of N x 3 arrays, +Z up.";
  py::register_exception<envpis::Error>(m, "Error", PyExc_RuntimeError);
  m.attr("__version__") = envpis::kVersion;  // the CMake project version
  m.def("simd_name", [] { return envpis::to_string(envpis::simd_resolve(envpis::Simd::Best)); },
        "The widest SIMD instruction set this CPU runs (avx512, avx2, sse2), which the module uses.");
  envpis_py::bind_equal_area(m);
  envpis_py::bind_environment_map(m);
  envpis_py::bind_importance_table(m);
  envpis_py::bind_bsdf_proxy(m);
  envpis_py::bind_product_sampler(m);
  envpis_py::bind_product_cache(m);
  envpis_py::bind_portals(m);
  envpis_py::bind_batch(m);
}
