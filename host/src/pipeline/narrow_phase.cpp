#include <cstreams/errors.hpp>
#include <cstreams/pipeline/narrow_phase.hpp>
#include <cstreams/runtime/context.hpp>

#include <cmath>
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

namespace {

// Deep enough for the depth-first search to reach boxes as small as the precision
// allows along the current path; running out still answers conservatively.
int stack_size(Precision p) { return p == Precision::single ? 96 : 192; }

}  // namespace

std::string solver_build_options(const SolverOptions& o)
{
  std::string options = "-DCS_REAL_DOUBLE=" + std::to_string(o.precision == Precision::double_) +
                        " -DCS_SOLVER=" + std::to_string(o.solver == Solver::conservative) +
                        " -DCS_STACK_SIZE=" + std::to_string(stack_size(o.precision));
  // Subnormal floats run at a fraction of the speed on CPUs; the float bounds already
  // widen every result by FLT_MIN, which covers anything flushed to zero.
  if (o.precision == Precision::single) options += " -cl-denorms-are-zero";
  return options;
}

float float_above(double x)
{
  return x > 0 ? std::nextafter(float(x), std::numeric_limits<float>::infinity()) : 0.0f;
}

namespace {

template <class Real> void pack(const std::vector<Query>& queries, std::vector<Real>& out)
{
  out.resize(queries.size() * 24);
  std::size_t i = 0;
  for (const auto& q : queries)
    for (const auto& p : q)
      for (int k = 0; k < 3; ++k) out[i++] = static_cast<Real>(p[k]);  // round to nearest
}

}  // namespace

DeviceSolver::DeviceSolver(runtime::Context& context, const SolverOptions& options)
    : context_(context), options_(options)
{
  if (options.precision == Precision::double_ && !context.device().fp64)
    throw Error("device " + context.device().name + " has no double precision; use the single-precision solver");
  if (!(options.tolerance > 0)) throw InputError("solver tolerance must be positive");
  if (!(options.min_separation >= 0)) throw InputError("minimum separation must not be negative");
  context.programs().add_sources(ccd_kernel_sources());
  kernel_ = context.programs().kernel("ccd/narrow_phase.cl", "cs_narrow_phase", solver_build_options(options));
}

std::vector<ElementaryResult> DeviceSolver::solve(ContactKind kind, const std::vector<Query>& queries,
                                                  std::uint64_t* kernel_ns)
{
  const std::size_t n = queries.size();
  std::vector<ElementaryResult> results(n);
  if (n == 0) {
    if (kernel_ns) *kernel_ns = 0;
    return results;
  }
  const bool dp = options_.precision == Precision::double_;
  for (std::size_t i = 0; i < n; ++i)
    for (const auto& p : queries[i]) {
      if (!p.allFinite()) throw InputError("query " + std::to_string(i) + " has a NaN or infinite coordinate");
      if (!dp && p.cwiseAbs().maxCoeff() > double(std::numeric_limits<float>::max()))
        throw InputError("query " + std::to_string(i) + " has a coordinate too large for the single-precision solver");
    }
  const std::size_t real_bytes = dp ? 8 : 4;
  runtime::ensure_capacity(context_, queries_, n * 24 * real_bytes, "queries");
  runtime::ensure_capacity(context_, status_, n * 4, "query status");
  runtime::ensure_capacity(context_, toi_, n * real_bytes, "times of impact");
  if (dp) {
    std::vector<double> packed;
    pack(queries, packed);
    context_.write(queries_, packed.data(), packed.size() * 8);
  } else {
    std::vector<float> packed;
    pack(queries, packed);
    context_.write(queries_, packed.data(), packed.size() * 4);
  }
  const cl_uint exact = dp;  // doubles are the data itself; floats were rounded
  unsigned index = 0;
  kernel_.set_arg(index++, queries_);
  kernel_.set_arg(index++, cl_uint(n));
  kernel_.set_arg(index++, cl_uint(kind == ContactKind::vertex_face));
  kernel_.set_arg(index++, exact);
  if (dp) {
    kernel_.set_arg(index++, options_.tolerance);
    kernel_.set_arg(index++, options_.min_separation);
  } else {
    kernel_.set_arg(index++, float_above(options_.tolerance));
    kernel_.set_arg(index++, float_above(options_.min_separation));
  }
  kernel_.set_arg(index++, cl_uint(options_.max_iterations));
  kernel_.set_arg(index++, cl_uint(options_.filter));
  kernel_.set_arg(index++, status_);
  kernel_.set_arg(index++, toi_);
  runtime::Timeline timeline;
  context_.launch(kernel_, n, context_.work_group_size(), kernel_ns ? &timeline : nullptr, "narrow phase");

  std::vector<std::uint32_t> status(n);
  context_.read(status_, status.data(), n * 4);
  std::vector<double> toi(n);
  if (dp) {
    context_.read(toi_, toi.data(), n * 8);
  } else {
    std::vector<float> f(n);
    context_.read(toi_, f.data(), n * 4);
    toi.assign(f.begin(), f.end());
  }
  for (std::size_t i = 0; i < n; ++i) results[i] = {QueryStatus(status[i]), toi[i]};
  if (kernel_ns) *kernel_ns = timeline.resolve().front().nanoseconds;
  return results;
}

}  // namespace cstreams
