#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/pipeline/option_checks.hpp>
#include <cstreams/runtime/context.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace cstreams {

const char* to_string(Solver s) noexcept { return s == Solver::cubic ? "cubic" : "conservative"; }
const char* to_string(Precision p) noexcept { return p == Precision::single ? "single" : "double"; }

Solver parse_solver(const std::string& text)
{
  if (text == "cubic") return Solver::cubic;
  if (text == "conservative") return Solver::conservative;
  throw InputError("unknown solver '" + text + "' (cubic or conservative)");
}

Precision parse_precision(const std::string& text)
{
  if (text == "single" || text == "float" || text == "f32") return Precision::single;
  if (text == "double" || text == "f64") return Precision::double_;
  throw InputError("unknown precision '" + text + "' (single or double)");
}

std::string solver_build_options(const SolverOptions& o)
{
  std::string options = "-DCS_REAL_DOUBLE=" + std::to_string(o.precision == Precision::double_) +
                        " -DCS_SOLVER=" + std::to_string(o.solver == Solver::conservative);
  // Subnormal floats run at a fraction of the speed on CPUs; the float bounds already
  // widen every result by FLT_MIN, which covers anything flushed to zero.
  if (o.precision == Precision::single) options += " -cl-denorms-are-zero";
  return options;
}

float float_above(double x)
{
  return x > 0 ? std::nextafter(float(x), std::numeric_limits<float>::infinity()) : 0.0f;
}

// One kind's queries as the pipeline sees candidates: query i owns points 4i..4i+3;
// a vertex-face query is the pair (vertex 4i, face i), an edge-edge one the pair
// (edge 2i, edge 2i + 1).
struct DeviceSolver::Graph {
  Graph(runtime::Context& context, const SolverOptions& options, ContactKind kind) : kind(kind)
  {
    using namespace runtime;
    const std::size_t real_bytes = options.precision == Precision::double_ ? 8 : 4;
    StreamGraph g;
    TestInputs in;
    in.x0 = g.fixed("x0", 3 * real_bytes, 0);
    in.x1 = g.fixed("x1", 3 * real_bytes, 0);
    in.faces = g.fixed("faces", 12, 0);
    in.edges = g.fixed("edges", 8, 0);
    in.exact_floats = g.param("queries are floats", 4);
    const GraphDevice device = graph_device(context);
    if (options.precision == Precision::single && escalates(options, device)) {
      x0_exact = in.x0_exact = g.fixed("x0 double", 24, 0);
      x1_exact = in.x1_exact = g.fixed("x1 double", 24, 0);
    }
    pairs = g.fixed("queries", 8, 0);
    culled = g.fixed("culled by the filter", 4, 0);
    in.candidates = {{pairs, kind}};
    auto& filter = g.pass("filter", {"ccd/narrow_phase_pairs.cl", "cs_filter_flags", solver_build_options(options)})
                       .launch_over(pairs)
                       .write(culled);
    real_arg(pair_kernel_args(filter, in, pairs, kind, options.precision), options.min_separation, options.precision)
        .arg(value_of(cl_uint(options.filter)))
        .arg(buffer_of(culled));
    const auto as_guessed = [](std::size_t guess) { return guess; };
    for (const auto& c : add_elementary_tests(g, in, options, device, as_guessed, true).contacts)
      contacts.push_back(c.first);
    x0 = in.x0;
    x1 = in.x1;
    exact_floats = in.exact_floats;
    faces = in.faces;
    edges = in.edges;
    scheduler = std::make_unique<Scheduler>(context, std::move(g));
  }

  ContactKind kind;
  runtime::StreamId x0, x1, x0_exact, x1_exact, faces, edges, pairs, culled;
  runtime::ParamId exact_floats;
  std::vector<runtime::StreamId> contacts;
  std::unique_ptr<runtime::Scheduler> scheduler;
};

namespace {

// The queries' points at the start of the step and at its end, four a query.
std::array<std::vector<Vec3>, 2> query_points(const std::vector<Query>& queries)
{
  std::array<std::vector<Vec3>, 2> x;
  for (auto& points : x) points.reserve(4 * queries.size());
  for (const auto& q : queries)
    for (int i = 0; i < 8; ++i) x[i / 4].push_back(q[i]);
  return x;
}

}  // namespace

void check_solver_options(const runtime::Context& context, const SolverOptions& options)
{
  check_option("SolverOptions::tolerance", options.tolerance, option_ranges::tolerance);
  check_option("SolverOptions::min_separation", options.min_separation, option_ranges::min_separation);
  check_option("SolverOptions::max_iterations", options.max_iterations, option_ranges::max_iterations);
  if (options.precision == Precision::double_ && !context.device().fp64)
    throw InputError("device " + context.device().name +
                     " has no double precision (neither cl_khr_fp64 nor cl_amd_fp64); use single precision");
}

DeviceSolver::DeviceSolver(runtime::Context& context, const SolverOptions& options)
    : context_(context), options_(options)
{
  check_solver_options(context, options);
  runtime::Context::ThreadGuard one_thread(context);
  context.programs().add_sources(ccd_kernel_sources());
}

DeviceSolver::~DeviceSolver() = default;

DeviceSolver::Graph& DeviceSolver::graph(ContactKind kind)
{
  auto& g = graphs_[kind == ContactKind::vertex_face ? 0 : 1];
  if (!g) g = std::make_unique<Graph>(context_, options_, kind);
  return *g;
}

std::vector<ElementaryResult> DeviceSolver::solve(ContactKind kind, const std::vector<Query>& queries,
                                                  std::uint64_t* kernel_ns)
{
  runtime::Context::ThreadGuard one_thread(context_);
  const std::size_t n = queries.size();
  std::vector<ElementaryResult> results(n);
  if (kernel_ns) *kernel_ns = 0;
  if (n == 0) return results;
  const bool dp = options_.precision == Precision::double_;
  for (std::size_t i = 0; i < n; ++i)
    for (const auto& p : queries[i]) {
      if (!p.allFinite()) throw InputError("query " + std::to_string(i) + " has a NaN or infinite coordinate");
      if (!dp && p.cwiseAbs().maxCoeff() > double(std::numeric_limits<float>::max()))
        throw InputError("query " + std::to_string(i) + " has a coordinate too large for the single-precision solver");
    }
  Graph& g = graph(kind);
  runtime::Scheduler& s = *g.scheduler;
  const auto m = std::uint32_t(n);
  std::vector<std::array<std::uint32_t, 3>> faces(n);
  std::vector<std::array<std::uint32_t, 2>> edges(2 * n), pairs(n);
  for (std::uint32_t i = 0; i < m; ++i) {
    faces[i] = {4 * i + 1, 4 * i + 2, 4 * i + 3};
    edges[2 * i] = {4 * i, 4 * i + 1};
    edges[2 * i + 1] = {4 * i + 2, 4 * i + 3};
    pairs[i] = kind == ContactKind::vertex_face ? std::array<std::uint32_t, 2>{4 * i, i}
                                                : std::array<std::uint32_t, 2>{2 * i, 2 * i + 1};
  }
  const auto [start, end] = query_points(queries);
  if (dp) {
    s.upload(g.x0, start);
    s.upload(g.x1, end);
  } else {
    const FloatPositions f0 = rounded_positions(start), f1 = rounded_positions(end);
    s.upload(g.x0, f0.rounded.data(), start.size());
    s.upload(g.x1, f1.rounded.data(), end.size());
    s.set(g.exact_floats, cl_uint(f0.exact && f1.exact));
    if (has(g.x0_exact)) {
      s.upload(g.x0_exact, start);
      s.upload(g.x1_exact, end);
    }
  }
  s.upload(g.faces, faces);
  s.upload(g.edges, edges);
  s.upload(g.pairs, pairs);
  s.resize(g.culled, n);
  s.run();

  const auto culled = s.download<std::uint32_t>(g.culled);
  for (std::size_t i = 0; i < n; ++i)
    if (culled[i]) results[i].status = QueryStatus::filtered;
  for (runtime::StreamId stream : g.contacts)
    for (const auto& c : s.download<std::array<std::uint32_t, 4>>(stream)) {
      const std::uint32_t i = kind == ContactKind::vertex_face ? c[1] : c[0] / 2;
      double t;
      if (dp) {
        const std::uint64_t bits = std::uint64_t(c[2]) | std::uint64_t(c[3]) << 32;
        std::memcpy(&t, &bits, sizeof bits);
      } else {
        float f;
        std::memcpy(&f, &c[2], sizeof f);
        t = f;
      }
      // CS_MARK_LIMIT: a limit's contact carries its time negated.
      results[i] = std::signbit(t) ? ElementaryResult{QueryStatus::limit, -t} : ElementaryResult{QueryStatus::collides, t};
    }
  if (kernel_ns)
    for (const auto& p : s.stats().passes) *kernel_ns += p.device_ns;
  return results;
}

}  // namespace cstreams
