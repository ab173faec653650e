// The array API for simulators (cstreams/simulation/) on numpy arrays, viewed in place.
// The GIL is released while the device works.
#include "bindings.hpp"
#include "numpy_arrays.hpp"
#include "records.hpp"

#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <pybind11/stl.h>

namespace cstreams::python {

namespace {

// E (edges in no face) is optional: None, or an (n, 2) array.
CollisionMesh collision_mesh(const py::array& V, const py::array& F, const std::optional<py::array>& E)
{
  return with_positions(V, "V", [&](const auto& v) {
    return with_indices(F, "F", 3, [&](const auto& f) {
      if (!E) return CollisionMesh(v, f);
      return with_indices(*E, "E", 2, [&](const auto& e) { return CollisionMesh(v, f, e); });
    });
  });
}

// Calls `call` with views of V0 and V1, without the GIL.
template <typename Call> auto on_motion(const py::array& V0, const py::array& V1, Call&& call)
{
  return with_positions(V0, "V0", [&](const auto& v0) {
    return with_positions(V1, "V1", [&](const auto& v1) {
      py::gil_scoped_release free;
      return call(v0, v1);
    });
  });
}

CcdParameters parameters(double min_distance, double tolerance, double max_iterations, double tmax)
{
  check_option("max_iterations", max_iterations, option_ranges::max_iterations);
  CcdParameters p;
  p.min_distance = min_distance;
  p.tolerance = tolerance;
  p.max_iterations = std::uint32_t(max_iterations);
  p.tmax = tmax;
  return p;
}

void bind_mesh_ccd(py::module_& m)
{
  const CcdParameters d;
  py::class_<MeshCcd>(m, "MeshCcd",
                      "Earliest times of impact, collision-free steps and step sizes of one mesh's linear motions "
                      "V0 -> V1; keeps its BVH and front between calls.")
      .def(py::init([](runtime::Context& device, const py::array& V, const py::array& F,
                       const std::optional<py::array>& E, const std::string& solver, const std::string& precision,
                       const std::string& front) {
             MeshCcdOptions o;
             o.solver = parse_solver(solver);
             o.precision = parse_precision(precision);
             o.front = parse_front_mode(front);
             return std::make_unique<MeshCcd>(device, collision_mesh(V, F, E), o);
           }),
           py::arg("context"), py::arg("V"), py::arg("F"), py::arg("E") = py::none(), py::arg("solver") = "conservative",
           py::arg("precision") = "single", py::arg("front") = "exact", py::keep_alive<1, 2>())
      .def(
          "toi",
          [](MeshCcd& c, const py::array& V0, const py::array& V1, double min_distance, double tolerance,
             double max_iterations, double tmax) {
            const CcdParameters p = parameters(min_distance, tolerance, max_iterations, tmax);
            return on_motion(V0, V1, [&](const auto& v0, const auto& v1) { return c.toi(v0, v1, p); });
          },
          py::arg("V0"), py::arg("V1"), py::arg("min_distance") = d.min_distance, py::arg("tolerance") = d.tolerance,
          py::arg("max_iterations") = double(d.max_iterations), py::arg("tmax") = d.tmax,
          "The earliest time in [0, tmax] at which two features come within min_distance; 1 where none does.")
      .def(
          "is_step_collision_free",
          [](MeshCcd& c, const py::array& V0, const py::array& V1, double min_distance) {
            return on_motion(V0, V1, [&](const auto& v0, const auto& v1) {
              return c.is_step_collision_free(v0, v1, min_distance);
            });
          },
          py::arg("V0"), py::arg("V1"), py::arg("min_distance") = 0.0)
      .def(
          "collision_free_stepsize",
          [](MeshCcd& c, const py::array& V0, const py::array& V1, double min_distance, double rescaling) {
            return on_motion(V0, V1, [&](const auto& v0, const auto& v1) {
              return c.collision_free_stepsize(v0, v1, min_distance, rescaling);
            });
          },
          py::arg("V0"), py::arg("V1"), py::arg("min_distance") = 0.0,
          py::arg("conservative_rescaling") = default_conservative_rescaling,
          "ipc-toolkit's compute_collision_free_stepsize: a step size in [0, 1].")
      .def_property_readonly("stats", [](const MeshCcd& c) { return stats_dict(c.stats()); });
}

void bind_mesh_proximity(py::module_& m)
{
  py::class_<MeshProximity>(m, "MeshProximity",
                            "Pairs of one mesh closer than dhat (with distances and closest features), or the "
                            "broad phase's candidates; keeps its BVH and front between calls.")
      .def(py::init([](runtime::Context& device, const py::array& V, const py::array& F,
                       const std::optional<py::array>& E, const std::string& precision, const std::string& front) {
             MeshProximityOptions o;
             o.precision = parse_precision(precision);
             o.front = parse_front_mode(front);
             return std::make_unique<MeshProximity>(device, collision_mesh(V, F, E), o);
           }),
           py::arg("context"), py::arg("V"), py::arg("F"), py::arg("E") = py::none(), py::arg("precision") = "double",
           py::arg("front") = "exact", py::keep_alive<1, 2>())
      .def(
          "close_pairs",
          [](MeshProximity& p, const py::array& V, double dhat) {
            const std::vector<ClosePair>* pairs = nullptr;
            with_positions(V, "V", [&](const auto& v) {
              py::gil_scoped_release free;
              pairs = &p.close_pairs(v, dhat);
              return 0;
            });
            return records(close_pair_dtype(), pairs->data(), pairs->size());
          },
          py::arg("V"), py::arg("dhat"),
          "A structured array: kind (0 vertex-face, 1 edge-edge), object_a, object_b, a, b, v, type, distance.")
      .def(
          "candidates",
          [](MeshProximity& p, const py::array& V, double radius) {
            const CandidateBlock block = with_positions(V, "V", [&](const auto& v) {
              py::gil_scoped_release free;
              return p.candidates(v, radius);
            });
            py::array_t<std::uint32_t> vf({py::ssize_t(block.vf.size()), py::ssize_t(2)});
            py::array_t<std::uint32_t> ee({py::ssize_t(block.ee.size()), py::ssize_t(2)});
            static_assert(sizeof(VertexFace) == 8 && sizeof(EdgeEdge) == 8);
            if (!block.vf.empty()) std::memcpy(vf.mutable_data(), block.vf.data(), block.vf.size() * 8);
            if (!block.ee.empty()) std::memcpy(ee.mutable_data(), block.ee.data(), block.ee.size() * 8);
            return py::make_tuple(vf, ee);
          },
          py::arg("V"), py::arg("radius"), "(vertex-face pairs, edge-edge pairs) whose boxes come within radius.")
      .def_property_readonly("stats", [](const MeshProximity& p) { return stats_dict(p.stats()); });
}

}  // namespace

void bind_simulation(py::module_& m)
{
  bind_mesh_ccd(m);
  bind_mesh_proximity(m);
  m.attr("POINT_TRIANGLE_TYPES") = py::make_tuple("p_t0", "p_t1", "p_t2", "p_e0", "p_e1", "p_e2", "p_t");
  m.attr("EDGE_EDGE_TYPES") =
      py::make_tuple("ea0_eb0", "ea0_eb1", "ea1_eb0", "ea1_eb1", "ea_eb0", "ea_eb1", "ea0_eb", "ea1_eb", "ea_eb");
}

}  // namespace cstreams::python
