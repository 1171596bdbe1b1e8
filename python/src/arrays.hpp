// numpy <-> limn's flat arrays: views without copies out of a mesh, checked copies in.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <vector>

namespace limn::py_bind {

namespace py = pybind11;

/// A numpy view of `v` (no copy) shaped (v.size() / cols, cols), or (v.size(),) when cols is 0;
/// `owner` is kept alive by the array (its `base`). Writable: the view edits the vector.
template <class T>
py::array_t<T> view(std::vector<T>& v, size_t cols, py::handle owner) {
  std::vector<py::ssize_t> shape, strides;
  if (cols == 0) {
    shape = {py::ssize_t(v.size())};
    strides = {py::ssize_t(sizeof(T))};
  } else {
    shape = {py::ssize_t(v.size() / cols), py::ssize_t(cols)};
    strides = {py::ssize_t(cols * sizeof(T)), py::ssize_t(sizeof(T))};
  }
  return py::array_t<T>(shape, strides, v.data(), owner);
}

/// A numpy array that takes over `v` (moved, not copied; freed with the array), shaped `shape`
/// (C order; the product must be v.size()).
template <class T>
py::array_t<T> owned(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(v));
  py::capsule free_it(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  std::vector<py::ssize_t> strides(shape.size(), py::ssize_t(sizeof(T)));
  for (size_t k = shape.size() - 1; k-- > 0;) strides[k] = strides[k + 1] * shape[k + 1];
  return py::array_t<T>(shape, strides, heap->data(), free_it);
}

/// `obj` (any array-like of numbers) as floats shaped (n, cols), or (n,) when cols is 0, copied.
/// TypeError for non-numbers; limn.InputError (ValueError) naming `what` for a wrong shape or a
/// value that is not finite.
std::vector<float> floats(py::handle obj, const char* what, size_t cols);

/// `obj` (any array-like of integers) as indices shaped (n, cols) or (n,), copied. TypeError for
/// non-integers; InputError naming `what` for a wrong shape, a negative index or one past
/// `bound` (no check when bound is 0).
std::vector<uint32_t> indices(py::handle obj, const char* what, size_t cols, size_t bound = 0);

}  // namespace limn::py_bind
