// SPDX-License-Identifier: Apache-2.0
// Batched product sampling over N shading points: one prepare() and one sample() (or pdf()) per point,
// run across TBB threads with the GIL released, one ProductSampler per thread. Each point's result
// is exactly what the per-point API returns for it: prepare() depends only on the point.
#include <envpis/product_sampler.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <string>

#include "module.h"
#include "proxy_rows.h"

namespace envpis_py {

namespace {

using envpis::ProductSampler;
using envpis::ProductSamplerOptions;

// The shading points: normals, wo and proxies, each N rows or one row shared by all points.
struct ShadingPoints {
  RowInput n, wo, proxy;
};

ShadingPoints shading_points(py::handle normals, py::handle wo, py::handle proxies, py::ssize_t count) {
  ShadingPoints s{row_input(normals, "normals", 3), row_input(wo, "wo", 3), proxy_rows(proxies)};
  const std::pair<const RowInput*, const char*> inputs[] = {{&s.n, "normals"}, {&s.wo, "wo"}, {&s.proxy, "proxies"}};
  for (const auto& [in, name] : inputs)
    if (in->count != 1 && in->count != count)
      throw py::value_error(std::string(name) + " has " + std::to_string(in->count) + " rows, expected " +
                            std::to_string(count) + " (one per shading point) or 1 (shared)");
  return s;
}

// Runs body(sampler, i) for i in [0, n) after preparing sampler for point i, on `threads` threads
// (0: TBB's default).
template <class Body>
void for_each_point(const envpis::ImportanceTable& table, const ProductSamplerOptions& options,
                    const ShadingPoints& pts, py::ssize_t n, int threads, Body body) {
  tbb::enumerable_thread_specific<ProductSampler> samplers([&] { return ProductSampler(table, options); });
  const auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(n), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        ProductSampler& s = samplers.local();
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const float *nv = pts.n.row(i), *wv = pts.wo.row(i);
                          s.prepare({nv[0], nv[1], nv[2]}, {wv[0], wv[1], wv[2]}, proxy_from_row(pts.proxy.row(i)));
                          body(s, i);
                        }
                      });
  };
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(run);
  } else {
    run();
  }
}

int thread_count(int threads) {
  if (threads < 0) throw py::value_error("threads must be >= 0 (0: all cores)");
  return threads;
}

py::tuple product_sample(const envpis::ImportanceTable& table, py::handle normals, py::handle wo, py::handle proxies,
                         py::handle u, const ProductSamplerOptions& options, int threads) {
  const FloatArray us = rows(u, "u", 2);
  const py::ssize_t n = us.shape(0);
  const ShadingPoints pts = shading_points(normals, wo, proxies, n);
  const int nthreads = thread_count(threads);
  static_cast<void>(ProductSampler(table, options));  // invalid options raise here, not on a worker thread
  py::array_t<float> dirs = new_array(n, 3), pdf = new_array(n);
  const float* src = us.data();
  float *d = dirs.mutable_data(), *p = pdf.mutable_data();
  {
    py::gil_scoped_release release;
    for_each_point(table, options, pts, n, nthreads, [&](const ProductSampler& s, std::size_t i) {
      const envpis::DirectionSample r = s.sample({src[2 * i], src[2 * i + 1]});
      d[3 * i] = r.direction.x, d[3 * i + 1] = r.direction.y, d[3 * i + 2] = r.direction.z;
      p[i] = r.pdf;
    });
  }
  return py::make_tuple(dirs, pdf);
}

py::array_t<float> product_pdf(const envpis::ImportanceTable& table, py::handle normals, py::handle wo,
                               py::handle proxies, py::handle dirs, const ProductSamplerOptions& options,
                               int threads) {
  const FloatArray ds = rows(dirs, "dirs", 3);
  const py::ssize_t n = ds.shape(0);
  const ShadingPoints pts = shading_points(normals, wo, proxies, n);
  const int nthreads = thread_count(threads);
  static_cast<void>(ProductSampler(table, options));  // invalid options raise here, not on a worker thread
  py::array_t<float> pdf = new_array(n);
  const float* src = ds.data();
  float* p = pdf.mutable_data();
  {
    py::gil_scoped_release release;
    for_each_point(table, options, pts, n, nthreads, [&](const ProductSampler& s, std::size_t i) {
      p[i] = s.pdf({src[3 * i], src[3 * i + 1], src[3 * i + 2]});
    });
  }
  return pdf;
}

}  // namespace

void bind_batch(py::module_& m) {
  const ProductSamplerOptions d;
  m.def("product_sample", &product_sample, py::arg("table"), py::arg("normals"), py::arg("wo"), py::arg("proxies"),
        py::arg("u"), py::arg("options") = d, py::arg("threads") = 0,
        "Batched product sampling: for each of N shading points (normals N x 3, wo N x 3, proxies N x 7 "
        "in PROXY_FIELDS order, a structured array or a list of BsdfProxy; any of them may be one row "
        "shared by all points), prepare a ProductSampler and draw one sample with u (N x 2). Returns "
        "(directions N x 3, pdfs N); pdf 0 means no sample (e.g. a zero or NaN normal). Runs on "
        "`threads` threads (0: all cores) without the GIL.");
  m.def("product_pdf", &product_pdf, py::arg("table"), py::arg("normals"), py::arg("wo"), py::arg("proxies"),
        py::arg("dirs"), py::arg("options") = d, py::arg("threads") = 0,
        "Batched product pdf: the density (solid angle) product_sample would have at dirs (N x 3), per "
        "shading point. Returns N pdfs.");
  py::object cls = m.attr("ProductSampler");
  cls.attr("sample_batch") = py::staticmethod(m.attr("product_sample"));
  cls.attr("pdf_batch") = py::staticmethod(m.attr("product_pdf"));
}

}  // namespace envpis_py
