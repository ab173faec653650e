// Elementary queries (eight points: a vertex and a face, or two edges, at both ends of
// the step) through the device solvers, as `cstreams accuracy` runs them.
#include "bindings.hpp"

#include <cstreams/io/query_io.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/runtime/context.hpp>

#include <pybind11/numpy.h>

namespace cstreams::python {

namespace {

ContactKind kind_of(const std::string& kind)
{
  if (kind == "vf" || kind == "vertex-face") return ContactKind::vertex_face;
  if (kind == "ee" || kind == "edge-edge") return ContactKind::edge_edge;
  throw InputError("kind: '" + kind + "' is neither vf (vertex-face) nor ee (edge-edge)");
}

std::vector<Query> queries_of(const py::array& points)
{
  if (points.ndim() != 3 || points.shape(1) != 8 || points.shape(2) != 3 || !py::isinstance<py::array_t<double>>(points))
    throw InputError("points: wants an (n, 8, 3) array of float64");
  const auto p = py::array_t<double, py::array::forcecast>(points).unchecked<3>();
  std::vector<Query> out(std::size_t(p.shape(0)));
  for (py::ssize_t q = 0; q < p.shape(0); ++q)
    for (py::ssize_t k = 0; k < 8; ++k) out[std::size_t(q)][std::size_t(k)] = Vec3(p(q, k, 0), p(q, k, 1), p(q, k, 2));
  return out;
}

}  // namespace

void bind_queries(py::module_& m)
{
  m.def(
      "read_queries",
      [](const std::string& path) {
        const std::vector<LabeledQuery> queries = read_queries(path);
        py::array_t<double> points({py::ssize_t(queries.size()), py::ssize_t(8), py::ssize_t(3)});
        py::array_t<bool> collides(py::ssize_t(queries.size()));
        auto p = points.mutable_unchecked<3>();
        auto c = collides.mutable_unchecked<1>();
        for (std::size_t q = 0; q < queries.size(); ++q) {
          for (int k = 0; k < 8; ++k)
            for (int d = 0; d < 3; ++d) p(py::ssize_t(q), k, d) = queries[q].points[std::size_t(k)][d];
          c(py::ssize_t(q)) = queries[q].collides;
        }
        return py::make_tuple(points, collides);
      },
      py::arg("path"), "A query CSV as (points (n, 8, 3) float64, collides (n,) bool: the truth column, or False).");

  const SolverOptions d;
  py::class_<DeviceSolver>(m, "QuerySolver",
                           "The device's elementary solvers over batches of queries, as the pipeline runs them.")
      .def(py::init([](runtime::Context& device, const std::string& solver, const std::string& precision,
                       double tolerance, double min_separation, std::uint32_t max_iterations, bool escalate) {
             SolverOptions o;
             o.solver = parse_solver(solver);
             o.precision = parse_precision(precision);
             o.tolerance = tolerance;
             o.min_separation = min_separation;
             o.max_iterations = max_iterations;
             o.escalate = escalate;
             return std::make_unique<DeviceSolver>(device, o);
           }),
           py::arg("context"), py::arg("solver") = "conservative", py::arg("precision") = "single",
           py::arg("tolerance") = d.tolerance, py::arg("min_separation") = 0.0,
           py::arg("max_iterations") = d.max_iterations, py::arg("escalate") = d.escalate, py::keep_alive<1, 2>())
      .def(
          "solve",
          [](DeviceSolver& s, const std::string& kind, const py::array& points) {
            const ContactKind k = kind_of(kind);
            const std::vector<Query> queries = queries_of(points);
            std::vector<ElementaryResult> results;
            {
              py::gil_scoped_release free;
              results = s.solve(k, queries);
            }
            py::array_t<bool> collides(py::ssize_t(results.size()));
            py::array_t<double> toi(py::ssize_t(results.size()));
            py::array_t<std::uint32_t> status(py::ssize_t(results.size()));
            for (std::size_t i = 0; i < results.size(); ++i) {
              collides.mutable_at(py::ssize_t(i)) = results[i].collides();
              toi.mutable_at(py::ssize_t(i)) = results[i].toi;
              status.mutable_at(py::ssize_t(i)) = std::uint32_t(results[i].status);
            }
            return py::make_tuple(collides, toi, status);
          },
          py::arg("kind"), py::arg("points"),
          "(collides, toi, status) per query; status 0 separate, 1 collides, 2 filtered, 3 a solver limit.");
}

}  // namespace cstreams::python
