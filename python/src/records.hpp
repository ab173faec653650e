#pragma once
// C++ records handed to Python as numpy structured arrays of the same layout, copied
// once: contacts and close pairs, and the statistics of a call as a dict.
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/proximity.hpp>

#include <pybind11/numpy.h>

#include <cstring>
#include <vector>

namespace cstreams::python {

namespace py = pybind11;

py::dtype contact_dtype();     // kind, object_a, object_b, v (4), toi
py::dtype close_pair_dtype();  // kind, object_a, object_b, a, b, v (4), type, distance

template <typename T> py::array records(const py::dtype& dtype, const T* data, std::size_t n)
{
  py::array out(dtype, std::vector<py::ssize_t>{py::ssize_t(n)}, std::vector<py::ssize_t>{});
  if (n) std::memcpy(out.mutable_data(), data, n * sizeof(T));
  return out;
}

py::dict stats_dict(const DetectorStats& s);

}  // namespace cstreams::python
