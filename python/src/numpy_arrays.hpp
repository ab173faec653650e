#pragma once
// numpy arrays as the C++ array API takes them, viewed in place: positions (n, 3) of
// float64 or float32 and indices (m, k) of int32 or int64, in C or Fortran order. Any
// other shape, dtype or layout is a ValueError (cstreams.InputError) naming the argument
// and what it wanted. The views read the array's memory: the array must outlive them.
#include <cstreams/errors.hpp>

#include <Eigen/Core>
#include <pybind11/numpy.h>

#include <string>

namespace cstreams::python {

namespace py = pybind11;

template <typename Scalar>
using View = Eigen::Map<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>, 0,
                        Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;

// Checks `a` against the shape (any rows, `cols` columns) and calls `use` with an Eigen
// view of it in its own scalar type, which must be First or Second.
template <typename First, typename Second, typename Use>
auto with_view(const py::array& a, const char* name, py::ssize_t cols, const char* wanted, Use&& use)
{
  const auto fail = [&](const std::string& got) [[noreturn]] {
    throw InputError(std::string(name) + ": wants " + wanted + ", got " + got);
  };
  if (a.ndim() != 2 || a.shape(1) != cols) {
    std::string shape = "shape (";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(a.shape(d));
    fail(shape + (a.ndim() == 1 ? ",)" : ")"));
  }
  const bool c_order = a.flags() & py::array::c_style, f_order = a.flags() & py::array::f_style;
  if (!c_order && !f_order) fail("an array in neither C nor Fortran order");
  const auto view = [&](auto scalar) {
    using S = decltype(scalar);
    const py::ssize_t item = py::ssize_t(sizeof(S));
    return View<S>(static_cast<const S*>(a.data()), a.shape(0), cols,
                   Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(a.strides(1) / item, a.strides(0) / item));
  };
  if (py::isinstance<py::array_t<Second>>(a)) return use(view(Second{}));
  if (!py::isinstance<py::array_t<First>>(a)) fail("dtype " + std::string(py::str(a.dtype())));
  return use(view(First{}));
}

template <typename Use> auto with_positions(const py::array& a, const char* name, Use&& use)
{
  return with_view<double, float>(a, name, 3, "an (n, 3) array of float64 or float32, C or Fortran order",
                                  std::forward<Use>(use));
}

template <typename Use> auto with_indices(const py::array& a, const char* name, py::ssize_t cols, Use&& use)
{
  const std::string wanted = "an (n, " + std::to_string(cols) + ") array of int32 or int64, C or Fortran order";
  return with_view<std::int32_t, std::int64_t>(a, name, cols, wanted.c_str(), std::forward<Use>(use));
}

}  // namespace cstreams::python
