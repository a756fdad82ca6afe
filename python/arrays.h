// SPDX-License-Identifier: Apache-2.0
// NumPy argument checking for the bindings: every array argument goes through rows() or one_row(),
// which convert numbers to C-contiguous float32 and raise ValueError (never crash) for anything else.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>

#include "envpis/common.h"

namespace envpis_py {

namespace py = pybind11;
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// `obj` as float32 numbers: an ndarray or anything numpy.asarray takes (lists, float64, ints).
/// ValueError for strings, objects, booleans, complex numbers and whatever numpy cannot convert.
FloatArray as_floats(py::handle obj, const char* name);

/// An N x cols array (N >= 0). With allow_single, a 1-D array of `cols` numbers is one row.
/// Sets *single to whether it was such a 1-D row.
FloatArray rows(py::handle obj, const char* name, py::ssize_t cols, bool allow_single = false,
                bool* single = nullptr);

/// A per-shading-point input for the batched calls: N x cols, or one row (cols numbers, or 1 x cols)
/// that every point shares. `stride` is set to cols, or to 0 for a shared row.
struct RowInput {
  FloatArray array;
  const float* data = nullptr;
  py::ssize_t count = 0;  ///< rows given (1 for a shared row)
  py::ssize_t stride = 0; ///< floats between consecutive points' rows
  const float* row(std::size_t i) const { return data + i * static_cast<std::size_t>(stride); }
};
RowInput row_input(py::handle obj, const char* name, py::ssize_t cols);

/// Exactly 3 numbers (or a 1 x 3 array) as a vector; ValueError otherwise.
envpis::Vec3 vec3(py::handle obj, const char* name);
py::array_t<float> vec3_array(envpis::Vec3 v);

/// A table's top cells as a T x T array: value(c) for each cell c, or zeros when not valid.
template <class Value>
py::array_t<float> top_grid(int t, bool valid, const Value& value) {
  py::array_t<float> out({t, t});
  float* o = out.mutable_data();
  for (int c = 0; c < t * t; ++c) o[c] = valid ? value(c) : 0.0f;
  return out;
}

/// Fresh float32 arrays for results.
py::array_t<float> new_array(py::ssize_t n);
py::array_t<float> new_array(py::ssize_t n, py::ssize_t cols);

/// Applies f(const float* in_row, float* out_row) to every row of an N x in_cols array (or to one
/// row given as in_cols numbers) with the GIL released. Returns N x out_cols (N for out_cols 1), or
/// for one row out_cols numbers (a float for out_cols 1).
template <class F>
py::object map_rows(py::handle obj, const char* name, py::ssize_t in_cols, py::ssize_t out_cols, F f) {
  bool single = false;
  const FloatArray in = rows(obj, name, in_cols, true, &single);
  const py::ssize_t n = single ? 1 : in.shape(0);
  py::array_t<float> out = out_cols == 1 ? new_array(n) : new_array(n, out_cols);
  const float* src = in.data();
  float* dst = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) f(src + i * in_cols, dst + i * out_cols);
  }
  if (!single) return std::move(out);
  if (out_cols == 1) return py::float_(dst[0]);
  return out.reshape({out_cols});
}

/// Draws one direction per row of u (N x 2, or one pair) with sample(Point2) -> DirectionSample, the
/// GIL released. Returns (N x 3 directions, N pdfs), or (3 numbers, a float) for one pair.
template <class Sample>
py::tuple sample_rows(py::handle u, Sample sample) {
  bool single = false;
  const FloatArray in = rows(u, "u", 2, true, &single);
  const py::ssize_t n = single ? 1 : in.shape(0);
  py::array_t<float> dirs = new_array(n, 3), pdf = new_array(n);
  const float* src = in.data();
  float *d = dirs.mutable_data(), *p = pdf.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) {
      const envpis::DirectionSample r = sample(envpis::Point2{src[2 * i], src[2 * i + 1]});
      d[3 * i] = r.direction.x, d[3 * i + 1] = r.direction.y, d[3 * i + 2] = r.direction.z;
      p[i] = r.pdf;
    }
  }
  if (single) return py::make_tuple(dirs.reshape({3}), py::float_(p[0]));
  return py::make_tuple(dirs, pdf);
}

}  // namespace envpis_py
