#include "arrays.hpp"

#include <fmt/format.h>

#include <cmath>

#include "limn/mesh/mesh.hpp"

namespace limn::py_bind {

namespace {

// The array, with its shape checked: (n, cols) or (n,).
py::array shaped(py::handle obj, const char* what, size_t cols, const char* kinds,
                 const char* expected) {
  py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(fmt::format("{}: expected an array of {}", what, expected));
  const char kind = a.dtype().kind();
  bool ok = false;
  for (const char* k = kinds; *k; ++k) ok |= kind == *k;
  if (!ok)
    throw py::type_error(fmt::format("{}: expected {}, got dtype {}", what, expected,
                                     std::string(py::str(a.dtype()))));
  if (cols == 0 ? a.ndim() != 1 : (a.ndim() != 2 || size_t(a.shape(1)) != cols)) {
    std::string shape;
    for (py::ssize_t k = 0; k < a.ndim(); ++k)
      shape += fmt::format("{}{}", k ? ", " : "", a.shape(k));
    throw InputError(fmt::format("{}: expected shape {}, got ({})", what,
                                 cols == 0 ? std::string("(n,)") : fmt::format("(n, {})", cols),
                                 shape));
  }
  return a;
}

}  // namespace

std::vector<float> floats(py::handle obj, const char* what, size_t cols) {
  const py::array a = shaped(obj, what, cols, "fiu", "numbers");
  const auto f = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  std::vector<float> out(f.data(), f.data() + f.size());
  for (size_t i = 0; i < out.size(); ++i)
    if (!std::isfinite(out[i]))
      throw InputError(fmt::format("{}: value {} of row {} is not finite ({})", what,
                                   cols ? i % cols : 0, cols ? i / cols : i, out[i]));
  return out;
}

std::vector<uint32_t> indices(py::handle obj, const char* what, size_t cols, size_t bound) {
  const py::array a = shaped(obj, what, cols, "iu", "integers");
  const auto i64 = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  std::vector<uint32_t> out(size_t(i64.size()));
  const int64_t* p = i64.data();
  const int64_t top = bound ? int64_t(bound) : int64_t(UINT32_MAX);
  for (size_t i = 0; i < out.size(); ++i) {
    if (p[i] < 0 || p[i] >= top)
      throw InputError(
          fmt::format("{}: index {} at {} is out of range (0-{})", what, p[i], i, top - 1));
    out[i] = uint32_t(p[i]);
  }
  return out;
}

}  // namespace limn::py_bind
