// Scenes of several objects and their Detector, for users beyond one mesh: contacts as
// a numpy structured array. The GIL is released while the device works.
#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "records.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/simulation/arrays.hpp>

#include <pybind11/stl.h>

namespace cstreams::python {

namespace {

std::vector<Vec3> positions(const py::array& V, const char* name, std::size_t rows = 0)
{
  return with_positions(V, name, [&](const auto& v) { return positions_from(v, name, rows); });
}

// One object from a dict: name, faces (m, 3), positions (n, 3); optionally segments
// (k, 2), points (vertex ids), kind and self_collision.
ObjectDescription object_from_dict(const py::dict& d, std::size_t index)
{
  const std::string where = "objects[" + std::to_string(index) + "]";
  for (const char* key : {"name", "faces", "positions"})
    if (!d.contains(key)) throw InputError(where + ": needs \"" + key + "\"");
  ObjectDescription o;
  o.name = py::cast<std::string>(d["name"]);
  const std::string v_name = where + ".positions", f_name = where + ".faces";
  o.positions = positions(d["positions"].cast<py::array>(), v_name.c_str());
  o.faces = with_indices(d["faces"].cast<py::array>(), f_name.c_str(), 3, [&](const auto& f) {
    return indices_from<3>(f, f_name.c_str(), o.positions.size());
  });
  if (d.contains("segments")) {
    const std::string e_name = where + ".segments";
    o.segments = with_indices(d["segments"].cast<py::array>(), e_name.c_str(), 2, [&](const auto& e) {
      return indices_from<2>(e, e_name.c_str(), o.positions.size());
    });
  }
  if (d.contains("points")) {
    const std::string p_name = where + ".points";
    const auto points = py::array_t<std::int64_t, py::array::forcecast>(d["points"].cast<py::array>());
    for (py::ssize_t i = 0; i < points.size(); ++i) {
      const std::int64_t v = points.data()[i];
      if (v < 0 || std::uint64_t(v) >= o.positions.size())
        throw InputError(p_name + ": entry " + std::to_string(i) + " holds vertex " + std::to_string(v) + "; there are " +
                         std::to_string(o.positions.size()) + " positions");
      o.points.push_back(std::uint32_t(v));
    }
  }
  if (d.contains("kind")) o.kind = parse_object_kind(py::cast<std::string>(d["kind"]));
  if (d.contains("self_collision")) o.self_collision = py::cast<bool>(d["self_collision"]);
  return o;
}

std::unique_ptr<Detector> make_detector(runtime::Context& device, const py::list& objects, const std::string& solver,
                                        const std::string& precision, double tolerance, double min_separation,
                                        const std::string& front)
{
  SceneDescription scene;
  for (std::size_t i = 0; i < objects.size(); ++i) scene.add(object_from_dict(objects[i].cast<py::dict>(), i));
  DetectorOptions o;
  o.solver.solver = parse_solver(solver);
  o.solver.precision = parse_precision(precision);
  o.solver.tolerance = tolerance;
  o.solver.min_separation = min_separation;
  o.front = parse_front_mode(front);
  py::gil_scoped_release free;
  return std::make_unique<Detector>(device, std::move(scene), o);
}

}  // namespace

void bind_detector(py::module_& m)
{
  const SolverOptions d;
  py::class_<Detector>(m, "Detector",
                       "CCD of a scene of objects, step after step. objects: dicts with name, faces (m, 3), "
                       "positions (n, 3), and optionally segments (k, 2) and points (vertex ids) that collide as "
                       "rods and particles, kind (deformable, rigid, static) and self_collision.")
      .def(py::init(&make_detector), py::arg("context"), py::arg("objects"), py::arg("solver") = "conservative",
           py::arg("precision") = "single", py::arg("tolerance") = d.tolerance, py::arg("min_separation") = 0.0,
           py::arg("front") = "exact", py::keep_alive<1, 2>())
      .def("object", &Detector::object, py::arg("name"))
      .def(
          "set_positions",
          [](Detector& det, std::uint32_t object, const py::array& end) {
            det.set_positions(object, positions(end, "end"));
          },
          py::arg("object"), py::arg("end"), "The object's positions at the end of the next step.")
      .def(
          "set_step",
          [](Detector& det, std::uint32_t object, const py::array& start, const py::array& end) {
            det.set_step(object, positions(start, "start"), positions(end, "end"));
          },
          py::arg("object"), py::arg("start"), py::arg("end"), "Both ends of the object's next step.")
      .def(
          "detect",
          [](Detector& det, bool earliest_only) {
            py::gil_scoped_release free;
            det.detect(earliest_only ? Report::earliest_toi : Report::contacts);
          },
          py::arg("earliest_only") = false)
      .def(
          "contacts",
          [](const Detector& det) {
            const ContactSpan c = det.contacts();
            return records(contact_dtype(), c.data(), c.size());
          },
          "The last step's contacts: kind (0 vertex-face, 1 edge-edge), object_a, object_b, v (4), toi.")
      .def("earliest_toi", [](const Detector& det) { return py::array(py::cast(det.earliest_toi())); })
      .def_property_readonly("stats", [](const Detector& det) { return stats_dict(det.stats()); });
}

}  // namespace cstreams::python
