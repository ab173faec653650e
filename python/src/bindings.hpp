#pragma once
// What each binding file adds to the module.
#include <pybind11/pybind11.h>

namespace cstreams::python {

namespace py = pybind11;

void bind_simulation(py::module_& m);  // CollisionMesh's arrays, MeshCcd, MeshProximity
void bind_detector(py::module_& m);    // scenes of objects and Detector
void bind_queries(py::module_& m);     // query files and the elementary solvers

}  // namespace cstreams::python
