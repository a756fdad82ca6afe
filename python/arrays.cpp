// SPDX-License-Identifier: Apache-2.0
#include "arrays.h"

#include <string>

namespace envpis_py {

namespace {

[[noreturn]] void value_error(const std::string& msg) { throw py::value_error(msg); }

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

FloatArray as_floats(py::handle obj, const char* name) {
  py::array a = py::array::ensure(obj);
  if (!a) value_error(std::string(name) + " must be an array of numbers");
  // 'b' (bool), 'c' (complex), 'U'/'S' (strings), 'O' (objects), 'V' (structured) are refused: numpy
  // would turn some of them into floats silently ("1.5" -> 1.5, True -> 1, 1+2j -> 1).
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    value_error(std::string(name) + " must hold numbers, not dtype " + py::str(a.dtype()).cast<std::string>());
  FloatArray f = FloatArray::ensure(a);
  if (!f) value_error(std::string(name) + " cannot be converted to float32");
  return f;
}

FloatArray rows(py::handle obj, const char* name, py::ssize_t cols, bool allow_single, bool* single) {
  FloatArray a = as_floats(obj, name);
  const bool one = allow_single && a.ndim() == 1 && a.shape(0) == cols;
  if (single) *single = one;
  if (one) return a;
  if (a.ndim() != 2 || a.shape(1) != cols)
    value_error(std::string(name) + " must have shape (N, " + std::to_string(cols) + ")" +
                (allow_single ? " or (" + std::to_string(cols) + ",)" : "") + ", got " + shape_of(a));
  return a;
}

RowInput row_input(py::handle obj, const char* name, py::ssize_t cols) {
  RowInput in;
  bool single = false;
  in.array = rows(obj, name, cols, true, &single);
  in.data = in.array.data();
  in.count = single ? 1 : in.array.shape(0);
  in.stride = in.count == 1 ? 0 : cols;
  return in;
}

envpis::Vec3 vec3(py::handle obj, const char* name) {
  bool single = false;
  const FloatArray a = rows(obj, name, 3, true, &single);
  if (!single && a.shape(0) != 1) throw py::value_error(std::string(name) + " must be 3 numbers");
  return {a.data()[0], a.data()[1], a.data()[2]};
}

py::array_t<float> vec3_array(envpis::Vec3 v) {
  py::array_t<float> out(3);
  float* o = out.mutable_data();
  o[0] = v.x, o[1] = v.y, o[2] = v.z;
  return out;
}

py::array_t<float> new_array(py::ssize_t n) { return py::array_t<float>(n); }
py::array_t<float> new_array(py::ssize_t n, py::ssize_t cols) {
  return py::array_t<float>({n, cols});
}

}  // namespace envpis_py
