// The Python module `cstreams`: devices, contexts, meshes, the array API for simulators
// and scenes with a Detector, on numpy arrays. Each concept binds itself in its own file.
#include "bindings.hpp"

#include <cstreams/devices.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/runtime/context.hpp>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

namespace cstreams::python {

namespace {

// C++ exceptions as Python ones of the same names: bad input is a ValueError, every
// other failure a RuntimeError (cstreams.Error), each kind its own subclass.
void bind_errors(py::module_& m)
{
  // pybind11 tries translators last registered first: each subclass after Error.
  const auto& error = py::register_exception<runtime::Error>(m, "Error", PyExc_RuntimeError);
  py::register_exception<runtime::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<runtime::ClError>(m, "ClError", error.ptr());
  py::register_exception<runtime::BuildError>(m, "BuildError", error.ptr());
  py::register_exception<runtime::DeviceNotFound>(m, "DeviceNotFound", error.ptr());
  py::register_exception<runtime::DeviceMemoryExhausted>(m, "DeviceMemoryExhausted", error.ptr());
  py::register_exception<runtime::StreamLimitExceeded>(m, "StreamLimitExceeded", error.ptr());
  py::register_exception<runtime::RunStopped>(m, "RunStopped", error.ptr());
}

py::dict device_dict(const DeviceInfo& d)
{
  py::dict out;
  out["address"] = d.address();
  out["name"] = d.name;
  out["platform"] = d.platform_name;
  out["vendor"] = d.vendor;
  out["driver"] = d.driver_version;
  out["type"] = runtime::to_string(d.kind);
  out["compute_units"] = d.compute_units;
  out["global_memory_bytes"] = d.global_memory;
  out["fp64"] = d.fp64;
  return out;
}

void bind_devices(py::module_& m)
{
  m.def(
      "devices",
      []() {
        py::list out;
        for (const DeviceInfo& d : runtime::list_devices()) out.append(device_dict(d));
        return out;
      },
      "Every OpenCL device, as a dict (address, name, platform, type, compute units, memory, fp64).");
  py::class_<runtime::Context>(m, "Context",
                               "One OpenCL device, chosen by a filter as on the command line (pocl, nvidia, gpu, "
                               "0:1, a name); None takes CSTREAMS_DEVICE, else the first GPU. One thread at a time.")
      .def(py::init([](const std::optional<std::string>& filter) {
             return std::make_unique<runtime::Context>(filter ? *filter : filter_from_environment());
           }),
           py::arg("filter") = py::none())
      .def_property_readonly("device", [](const runtime::Context& c) { return device_dict(c.device()); });
}

void bind_meshes(py::module_& m)
{
  m.def(
      "read_mesh",
      [](const std::string& path) {
        const Mesh mesh = read_mesh(path);
        py::array_t<double> V({py::ssize_t(mesh.positions.size()), py::ssize_t(3)});
        py::array_t<std::int64_t> F({py::ssize_t(mesh.faces.size()), py::ssize_t(3)});
        auto v = V.mutable_unchecked<2>();
        auto f = F.mutable_unchecked<2>();
        for (std::size_t i = 0; i < mesh.positions.size(); ++i)
          for (int k = 0; k < 3; ++k) v(py::ssize_t(i), k) = mesh.positions[i][k];
        for (std::size_t i = 0; i < mesh.faces.size(); ++i)
          for (int k = 0; k < 3; ++k) f(py::ssize_t(i), k) = mesh.faces[i][std::size_t(k)];
        return py::make_tuple(V, F);
      },
      py::arg("path"), "A PLY or OBJ triangle mesh as (V, F): float64 (n, 3) positions and int64 (m, 3) faces.");
}

}  // namespace

}  // namespace cstreams::python

PYBIND11_MODULE(cstreams, m)
{
  using namespace cstreams::python;
  m.doc() = "Continuous collision detection and proximity between triangle meshes on any OpenCL device.";
  bind_errors(m);
  bind_devices(m);
  bind_meshes(m);
  bind_simulation(m);
  bind_detector(m);
  bind_queries(m);
}
