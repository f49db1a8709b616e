#pragma once
// array_view.hpp: read-only NumPy views of Eigen storage that a Python object keeps alive (no copies).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <vector>

namespace flexbody::python {

namespace py = pybind11;

/// A read-only array over `data` with the given shape and strides (in elements), whose base is `owner`: the array
/// keeps the owner alive, and writing to it raises ValueError.
template <class T>
py::array read_only(const T* data, const std::vector<py::ssize_t>& shape, const std::vector<py::ssize_t>& strides,
                    py::handle owner) {
  std::vector<py::ssize_t> bytes(strides.size());
  for (std::size_t k = 0; k < strides.size(); ++k) bytes[k] = strides[k] * static_cast<py::ssize_t>(sizeof(T));
  py::array view(py::dtype::of<T>(), shape, bytes, data, owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

/// An Eigen matrix or vector as it lies in memory: rows x cols in its own order (column-major Eigen matrices become
/// Fortran-ordered arrays), a vector as 1-D.
template <class Derived>
py::array view_of(const Eigen::PlainObjectBase<Derived>& m, py::handle owner) {
  using Scalar = typename Derived::Scalar;
  if constexpr (Derived::IsVectorAtCompileTime) return read_only<Scalar>(m.data(), {m.size()}, {1}, owner);
  const py::ssize_t rows = m.rows(), cols = m.cols();
  if constexpr (Derived::IsRowMajor) return read_only<Scalar>(m.data(), {rows, cols}, {cols, 1}, owner);
  return read_only<Scalar>(m.data(), {rows, cols}, {1, rows}, owner);
}

}  // namespace flexbody::python
