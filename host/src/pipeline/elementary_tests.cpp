// The elementary tests' passes of a stream graph: the cubic solver, or the conservative
// screen and refinement, and single precision's escalation to double.
#include "stream_args.hpp"

#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>

#include <functional>
#include <string>

namespace cstreams {

namespace {

// Positions, topology and whether the positions are the exact input, which every kernel
// over queries takes after its queries: double positions always are, float ones where
// the step's parameter says so.
runtime::PassSpec& geometry_args(runtime::PassSpec& pass, const TestInputs& in, Precision precision)
{
  using namespace runtime;
  pass.arg(buffer_of(in.x0)).arg(buffer_of(in.x1)).arg(buffer_of(in.faces)).arg(buffer_of(in.edges));
  return precision == Precision::double_ ? pass.arg(value_of(cl_uint(1))) : pass.arg(param_of(in.exact_floats));
}

}  // namespace

runtime::PassSpec& pair_kernel_args(runtime::PassSpec& pass, const TestInputs& in, runtime::StreamId pairs,
                                    ContactKind kind, Precision precision)
{
  using namespace runtime;
  pass.arg(buffer_of(pairs)).arg(count_of(pairs)).arg(value_of(cl_uint(kind == ContactKind::vertex_face)));
  return geometry_args(pass, in, precision);
}

runtime::PassSpec& real_arg(runtime::PassSpec& pass, double x, Precision precision)
{
  using runtime::value_of;
  return precision == Precision::double_ ? pass.arg(value_of(x)) : pass.arg(value_of(float_above(x)));
}

namespace {

using Sized = std::function<std::size_t(std::size_t)>;

// Whether the conservative screen runs in float on inputs rounded outward: in double
// precision, where the graph has the positions in float too (TestInputs::x0_float). The
// refinement then runs the non-penetration filter the screen left out.
bool screens_in_float(const TestInputs& in, const SolverOptions& solver)
{
  return solver.precision == Precision::double_ && has(in.x0_float);
}

// The cubic solver's one pass over every candidate stream.
void add_cubic_test(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver,
                    const std::string& options, const ContactStreams& contacts)
{
  using namespace runtime;
  const StreamId vf = contacts[0].first, ee = contacts[1].first;
  // In a scene of objects, in the steps that report earliest times alone, the test
  // lowers each object's time itself and skips the pairs that cannot lower it.
  const bool objects = has(in.earliest);
  const std::string cubic_options = options + (objects ? " -DCS_EARLIEST_ACROSS=1" : "");
  auto& test = g.pass("test candidates", {"ccd/narrow_phase_pairs.cl", "cs_cubic_pairs", cubic_options})
                   .emit(vf)
                   .emit(ee)
                   .emits_in_any_order()
                   .expect_items(0.25);
  over_streams(test, in.candidates, "the cubic solver");
  real_arg(real_arg(geometry_args(test, in, solver.precision), solver.tolerance, solver.precision),
           solver.min_separation, solver.precision)
      .arg(value_of(cl_uint(solver.filter)));
  if (objects)
    test.instead_while(in.earliest_only, "cs_cubic_earliest_pairs")
        .lower(in.earliest)
        .arg(buffer_of(in.vertex_object))
        .arg(buffer_of(in.earliest));
}

// The conservative solver refines what its screen leaves open as one work list, so
// that its rounds are paid once a step. This is the screen; it emits the queries it
// leaves open. In double it runs in float (inputs rounded outward, so that it settles
// only what is certain), at float's cost, and the refinement's seed and first round do
// in double what a second screen would: on n-body a screen in double after the float
// one settled 91 of the 1.19M pairs that the float one left open, for 0.42 ms.
runtime::StreamId add_conservative_screen(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver,
                                          const std::string& options, const Sized& sized)
{
  using namespace runtime;
  const StreamId open = g.variable("open queries", 16, sized(1024));
  const bool in_float = screens_in_float(in, solver);
  SolverOptions float_solver = solver;
  float_solver.precision = Precision::single;
  const std::string screen_options = in_float ? solver_build_options(float_solver) : options;
  auto& test = g.pass(in_float ? "test candidates in float" : "test candidates",
                      {"ccd/narrow_phase_pairs.cl", "cs_screen_pairs", screen_options})
                   .emit(open)
                   // The refinement answers each query on its own, so it takes them
                   // in any order.
                   .emits_in_any_order()
                   .expect_items(0.5);
  over_streams(test, in.candidates, "the conservative screen");
  if (in_float) {
    TestInputs rounded = in;
    rounded.x0 = in.x0_float;
    rounded.x1 = in.x1_float;
    real_arg(geometry_args(test, rounded, Precision::single), solver.min_separation, Precision::single);
  } else {
    real_arg(geometry_args(test, in, solver.precision), solver.min_separation, solver.precision);
  }
  test.arg(value_of(cl_uint(solver.filter)));
  return open;
}

constexpr std::size_t most_refinement_bytes = std::size_t(512) << 20;

// A refinement of queries in `precision`: one box a work-item, breadth first across the
// device (refine.cl). An item is a query index, its work and a box of six reals; the
// state of a query two keys of at most one real each (a float on devices without 64-bit
// atomics) and eight words, a ninth where it escalates, and in a scene of objects three
// more for the steps that report earliest times alone. On a CPU the state also keeps
// the query's function, 37 reals (CS_KEEP_FUNCTION in refine.cl). `in` holds positions
// of the precision; `objects`: it gives up, in earliest-only steps, the queries that
// cannot hold an object's earliest time.
runtime::PassSpec& add_refine_pass(runtime::StreamGraph& g, const std::string& name, const TestInputs& in,
                                   const SolverOptions& solver, Precision precision, const GraphDevice& device,
                                   const std::string& options, runtime::StreamId queries, bool objects,
                                   bool escalating, bool use_filter)
{
  using namespace runtime;
  // The round kernel is heavy in registers (255 a work-item in double on the H200): in
  // groups of 64 several groups share an SM, and 64 measured best against 32, 128 and
  // 256 (BENCHMARKS.md).
  constexpr std::size_t refine_group = 64;
  const std::size_t real_bytes = precision == Precision::double_ ? 8 : 4;
  runtime::Worklist boxes{"cs_refine_seed",
                          "cs_refine_round",
                          8 + 6 * real_bytes,
                          2 * real_bytes + 32 + (escalating ? 4 : 0) + (device.cpu ? 37 * real_bytes : 0),
                          device.refine_items,
                          refine_group};
  if (objects) {
    boxes.extra_state_bytes = 12;
    boxes.extra_state_while = in.earliest_only;
  }
  // A burst of open queries is refined in slices: the 1.5M-triangle sheet's surge step
  // (9.6M queries in double) held 1.8 GB of state and lists at once, more than half its
  // peak. A real step's refinement takes 60-230 MB.
  boxes.most_bytes = most_refinement_bytes;
  const std::string refine_options = options + (objects ? " -DCS_EARLIEST_ACROSS=1" : "") +
                                     (device.cpu ? " -DCS_KEEP_FUNCTION=1" : "") +
                                     (escalating ? " -DCS_ESCALATE=1" : "");
  auto& pass = g.pass(name, {"ccd/refine.cl", "cs_refine_finish", refine_options})
                   .launch_over(queries)
                   .refine(boxes)
                   .emits_in_any_order()
                   .expect_items(0.5);
  pass.arg(buffer_of(queries)).arg(count_of(queries));
  real_arg(real_arg(geometry_args(pass, in, precision), solver.tolerance, precision), solver.min_separation,
           precision)
      .arg(value_of(cl_uint(solver.max_iterations)))
      .arg(value_of(cl_uint(use_filter)));
  if (objects)
    pass.write(in.object_contacts)
        .arg(param_of(in.earliest_only))
        .arg(buffer_of(in.vertex_object))
        .arg(buffer_of(in.object_contacts));
  return pass;
}

// The refinement of the open queries, into the contacts; where the solver escalates,
// the queries it leaves undecided into `escalated`.
void add_refinement(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver, const GraphDevice& device,
                    const std::string& options, runtime::StreamId open, const ContactStreams& contacts,
                    runtime::StreamId escalated)
{
  const bool objects = has(in.object_contacts);
  const bool escalating = has(escalated);
  auto& pass = add_refine_pass(g, "refine open queries", in, solver, solver.precision, device, options, open, objects,
                               escalating, solver.filter && screens_in_float(in, solver));
  pass.emit(contacts[0].first).emit(contacts[1].first);
  if (escalating) pass.emit(escalated, 0.01);
}

// The escalated queries' refinement in double, on the exact positions, each query in
// full (no earliest-only giving up: the float refinement's contacts are not its to
// weigh). Its contacts carry float times rounded down, as the float ones do. The
// non-penetration filter, already passed in float, runs again in double, where it may
// cull a near miss.
void add_escalation(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver,
                    const GraphDevice& device, const std::string& mark_options, runtime::StreamId escalated,
                    const ContactStreams& contacts)
{
  TestInputs exact = in;
  exact.x0 = in.x0_exact;
  exact.x1 = in.x1_exact;
  SolverOptions in_double = solver;
  in_double.precision = Precision::double_;
  const std::string options = solver_build_options(in_double) + mark_options + " -DCS_CONTACT_FLOAT=1";
  add_refine_pass(g, "refine escalated queries in double", exact, solver, Precision::double_, device, options,
                  escalated, false, false, solver.filter)
      .emit(contacts[0].first)
      .emit(contacts[1].first);
}

}  // namespace

bool escalates(const SolverOptions& solver, const GraphDevice& device)
{
  return solver.solver == Solver::conservative && solver.precision == Precision::single && solver.escalate &&
         solver.min_separation == 0 && device.fp64;
}

TestStreams add_elementary_tests(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver,
                                 const GraphDevice& device, const std::function<std::size_t(std::size_t)>& sized,
                                 bool mark_limits)
{
  using namespace runtime;
  const std::string mark_options = mark_limits ? " -DCS_MARK_LIMIT=1" : "";
  const std::string options = solver_build_options(solver) + mark_options;
  // Every candidate stream goes through one pass: small streams (the orphans') in
  // launches of their own would each cost a launch, whatever their work.
  const StreamId vf = g.variable("vf contacts", 16, sized(256)), ee = g.variable("ee contacts", 16, sized(256));
  g.gather(vf);
  g.gather(ee);
  // Contacts are read sorted (contacts.cl), by their minimum (earliest.cl) or by their
  // query (narrow_phase.cpp), so their passes emit them in any order.
  TestStreams out;
  out.contacts = {{vf, ContactKind::vertex_face}, {ee, ContactKind::edge_edge}};
  if (solver.solver == Solver::cubic) {
    add_cubic_test(g, in, solver, options, out.contacts);
    return out;
  }
  const StreamId open = add_conservative_screen(g, in, solver, options, sized);
  const bool escalating = escalates(solver, device) && has(in.x0_exact);
  if (escalating) out.escalated = g.variable("escalated queries", 16, sized(256));
  add_refinement(g, in, solver, device, options, open, out.contacts, out.escalated);
  if (!escalating) return out;
  const ContactStreams escalated_contacts = {
      {g.variable("escalated vf contacts", 16, sized(64)), ContactKind::vertex_face},
      {g.variable("escalated ee contacts", 16, sized(64)), ContactKind::edge_edge}};
  for (const auto& c : escalated_contacts) g.gather(c.first);
  add_escalation(g, in, solver, device, mark_options, out.escalated, escalated_contacts);
  out.contacts.insert(out.contacts.end(), escalated_contacts.begin(), escalated_contacts.end());
  return out;
}

}  // namespace cstreams
