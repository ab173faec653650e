#include "stream_args.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/runtime/context.hpp>

#include <algorithm>

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

// A pass over every candidate (or contact) stream of a step in one launch
// (cs_cubic_pairs, cs_screen_pairs, cs_earliest_toi) launches over them all and takes
// their triples as its first arguments.
void over_streams(runtime::PassSpec& pass, const std::vector<std::pair<runtime::StreamId, ContactKind>>& streams,
                  const char* what)
{
  using namespace runtime;
  std::vector<StreamId> over;
  for (const auto& s : streams) over.push_back(s.first);
  bind_four_streams(streams, what, [&](StreamId stream, bool used, cl_uint vertex_face) {
    pass.arg(buffer_of(stream)).arg(used ? count_of(stream) : value_of(cl_uint(0))).arg(value_of(vertex_face));
  });
  pass.launch_over(over);
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

using ContactStreams = std::vector<std::pair<runtime::StreamId, ContactKind>>;
using Sized = std::function<std::size_t(std::size_t)>;

// Whether the conservative screen runs in float on inputs rounded outward: in double
// precision, where the graph has the positions in float too (TestInputs::x0_float). The
// refinement then runs the non-penetration filter the screen left out.
bool screens_in_float(const TestInputs& in, const SolverOptions& solver)
{
  return solver.precision == Precision::double_ && in.x0_float != runtime::StreamId{};
}

// The cubic solver's one pass over every candidate stream.
void add_cubic_test(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver,
                    const std::string& options, const ContactStreams& contacts)
{
  using namespace runtime;
  const StreamId vf = contacts[0].first, ee = contacts[1].first;
  // In a scene of objects, in the steps that report earliest times alone, the test
  // lowers each object's time itself and skips the pairs that cannot lower it.
  const bool objects = in.earliest != StreamId{};
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

// The refinement of the open queries: one box a work-item, breadth first across the
// device (refine.cl). An item is a query index, its work and a box of six reals; the
// state of a query two keys of at most one real each (a float on devices without 64-bit
// atomics) and eight words, and in a scene of objects three more for the steps that
// report earliest times alone. On a CPU the state also keeps the query's function, 37
// reals (CS_KEEP_FUNCTION in refine.cl).
void add_refinement(runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver, const GraphDevice& device,
                    const std::string& options, runtime::StreamId open, const ContactStreams& contacts)
{
  using namespace runtime;
  const StreamId vf = contacts[0].first, ee = contacts[1].first;
  // The round kernel is heavy in registers (255 a work-item in double on the H200): in
  // groups of 64 several groups share an SM, and 64 measured best against 32, 128 and
  // 256 (BENCHMARKS.md).
  constexpr std::size_t refine_group = 64;
  const bool in_float = screens_in_float(in, solver);
  const std::size_t real_bytes = solver.precision == Precision::double_ ? 8 : 4;
  runtime::Worklist boxes{"cs_refine_seed",
                          "cs_refine_round",
                          8 + 6 * real_bytes,
                          2 * real_bytes + 32 + (device.cpu ? 37 * real_bytes : 0),
                          device.refine_items,
                          refine_group};
  const bool objects = in.object_contacts != StreamId{};
  if (objects) {
    boxes.extra_state_bytes = 12;
    boxes.extra_state_while = in.earliest_only;
  }
  const std::string refine_options =
      options + (objects ? " -DCS_EARLIEST_ACROSS=1" : "") + (device.cpu ? " -DCS_KEEP_FUNCTION=1" : "");
  auto& pass = g.pass("refine open queries", {"ccd/refine.cl", "cs_refine_finish", refine_options})
                   .launch_over(open)
                   .refine(boxes)
                   .emit(vf)
                   .emit(ee)
                   .emits_in_any_order()
                   .expect_items(0.5);
  pass.arg(buffer_of(open)).arg(count_of(open));
  real_arg(real_arg(geometry_args(pass, in, solver.precision), solver.tolerance, solver.precision),
           solver.min_separation, solver.precision)
      .arg(value_of(cl_uint(solver.max_iterations)))
      .arg(value_of(cl_uint(solver.filter && in_float)));
  if (objects)
    pass.write(in.object_contacts)
        .arg(param_of(in.earliest_only))
        .arg(buffer_of(in.vertex_object))
        .arg(buffer_of(in.object_contacts));
}

}  // namespace

std::vector<std::pair<runtime::StreamId, ContactKind>> add_elementary_tests(
    runtime::StreamGraph& g, const TestInputs& in, const SolverOptions& solver, const GraphDevice& device,
    const std::function<std::size_t(std::size_t)>& sized, bool mark_limits)
{
  using namespace runtime;
  const std::string options = solver_build_options(solver) + (mark_limits ? " -DCS_MARK_LIMIT=1" : "");
  // Every candidate stream goes through one pass: small streams (the orphans') in
  // launches of their own would each cost a launch, whatever their work.
  const StreamId vf = g.variable("vf contacts", 16, sized(256)), ee = g.variable("ee contacts", 16, sized(256));
  g.gather(vf);
  g.gather(ee);
  // Contacts are read sorted (contacts.cl), by their minimum (earliest.cl) or by their
  // query (narrow_phase.cpp), so their passes emit them in any order.
  const ContactStreams contacts = {{vf, ContactKind::vertex_face}, {ee, ContactKind::edge_edge}};
  if (solver.solver == Solver::cubic) {
    add_cubic_test(g, in, solver, options, contacts);
  } else {
    const StreamId open = add_conservative_screen(g, in, solver, options, sized);
    add_refinement(g, in, solver, device, options, open, contacts);
  }
  return contacts;
}

namespace {

constexpr const char* broad_phase_program = "ccd/broad_phase.cl";

// Builds one scene's graph piece by piece; each step adds the streams and passes of
// one stage of the pipeline and leaves those a scene does not need unset.
struct GraphBuilder {
  GraphBuilder(const SceneLayout& layout, const DetectorOptions& options)
      : l(layout), solver(options.solver), options(options), t(layout.topology),
        exact_input(solver.precision == Precision::double_), separation(float_above(bounds_margin(options)))
  {
  }

  const SceneLayout& l;
  const SolverOptions& solver;
  const DetectorOptions& options;
  const Topology& t;
  const bool exact_input;
  const float separation;
  CcdGraph out;
  runtime::StreamGraph& g = out.graph;
  CcdStreams& s = out.streams;

  // Where the motion the broad phase sweeps starts: a proximity query has no motion,
  // and its boxes and culls take the end positions at both ends.
  runtime::StreamId start() const { return options.detects == Detects::close_pairs ? s.x1 : s.x0; }

  // Expected sizes only; every variable stream grows as its counter demands.
  std::size_t sized(std::size_t guess) const { return options.initial_capacity ? options.initial_capacity : guess; }

  void geometry_streams()
  {
    const std::size_t nv = t.vertex_count, nf = t.faces.size(), ne = t.edges.size(), nn = l.nodes.size();
    s.x0 = g.fixed("x0", 12, nv);
    s.x1 = g.fixed("x1", 12, nv);
    s.x_next = g.fixed("x next", 12, 0);
    s.x0_next = g.fixed("x0 next", 12, 0);
    s.exact_floats = g.param("positions are floats", 4);
    if (exact_input) {
      s.x0_double = g.fixed("x0 double", 24, nv);
      s.x1_double = g.fixed("x1 double", 24, nv);
      s.x_next_double = g.fixed("x next double", 24, 0);
      s.x0_next_double = g.fixed("x0 next double", 24, 0);
    }
    s.faces = g.fixed("faces", 12, nf);
    s.edges = g.fixed("edges", 8, ne);
    s.nodes = g.fixed("bvh nodes", 8, nn);
    s.face_words = g.fixed("face leaves and ownership", 4, nf);
    s.edge_boxes = g.fixed("edge bounds", 72, ne);
    s.node_boxes = g.fixed("bvh bounds", 72, nn);
  }

  // Swept bounds of the moving prefix and the refit of its trees; static objects'
  // bounds are uploaded once.
  void bounds_and_refit(std::size_t group, const RefitPlan& refit)
  {
    using namespace runtime;
    if (l.moving_faces == 0) return;
    const char* bounds = "ccd/bounds.cl";
    g.pass("swept bounds", {bounds, "cs_primitive_bounds"})
        .launch_items(l.moving_faces + l.moving_edges)
        .update(s.node_boxes)
        .write(s.edge_boxes)
        .arg(buffer_of(start()))
        .arg(buffer_of(s.x1))
        .arg(buffer_of(s.faces))
        .arg(buffer_of(s.edges))
        .arg(value_of(cl_uint(l.moving_faces)))
        .arg(value_of(cl_uint(l.moving_edges)))
        .arg(value_of(separation))
        .arg(buffer_of(s.face_words))
        .arg(buffer_of(s.node_boxes))
        .arg(buffer_of(s.edge_boxes));
    s.refit_ranges = g.fixed("refit ranges", 8, refit.ranges.size());
    for (const RefitBand& band : refit.bands) {
      const std::size_t last = band.top + band.levels - 1;
      const std::string name = band.levels == 1 ? "refit level " + std::to_string(band.top)
                                                : "refit levels " + std::to_string(band.top) + "-" + std::to_string(last);
      g.pass(name, {bounds, "cs_refit_levels"})
          .launch_items((l.levels[band.top + 1] - l.levels[band.top]) * group)
          .update(s.node_boxes)
          .arg(buffer_of(s.nodes))
          .arg(buffer_of(s.refit_ranges))
          .arg(value_of(cl_uint(band.first_range)))
          .arg(value_of(cl_uint(band.levels)))
          .arg(buffer_of(s.node_boxes));
    }
  }

  // The culls of the orphan pairs, then the front update (or search from fixed seeds)
  // down to triangle pairs and their decomposition into feature pairs.
  void broad_phase(std::size_t front_size, const GraphDevice& device)
  {
    const std::size_t nf = t.faces.size();
    const bool keep_front = options.front != FrontMode::none;
    const std::size_t guess = sized(std::max<std::size_t>(1024, nf));
    s.face_edges = g.fixed("face edges", 12, nf);
    if (keep_front) {
      s.front = g.variable("front", 8, sized(std::max(front_size, 4 * nf)));
      s.next_front = g.variable("next front", 8, sized(std::max(front_size, 4 * nf)));
      g.gather(s.next_front);
    } else {
      s.front = g.fixed("bvtt seeds", 8, front_size);
    }
    s.level_cap = g.param("front level cap", 4);
    s.searches_cut = g.fixed("searches cut", 4, 2);
    s.triangle_pairs = g.variable("triangle pairs", 8, guess);
    g.within_run(s.triangle_pairs);  // only the decomposition reads them
    s.vf = g.variable("vf candidates", 8, guess);
    s.ee = g.variable("ee candidates", 8, guess);
    orphan_culls();
    // One build of the program serves both its passes, two where their registers are
    // capped apart (GraphDevice).
    const std::string front_option = "-DCS_KEEP_FRONT=" + std::to_string(int(keep_front));
    front_update(keep_front, front_option, device);
    decomposition(front_option, device);
  }

  // The orphan pairs' culls need no front: they go first, before the front update and
  // what it emits take the device's memory. They emit what they keep in any order
  // (orphans.cl).
  void orphan_culls()
  {
    using namespace runtime;
    // Each returns its pass, where there are pairs, for the arguments of its kernel.
    auto cull_orphans = [&](const char* name, const char* kept_name, std::size_t count, const char* kernel,
                            StreamId& pairs, StreamId& kept) -> PassSpec* {
      if (count == 0) return nullptr;
      pairs = g.fixed(name, 8, count);
      kept = g.variable(kept_name, 8, sized(std::max<std::size_t>(256, count / 8)));
      return &g.pass(std::string("cull ") + name, {"ccd/orphans.cl", kernel})
                  .launch_over(pairs)
                  .emit(kept)
                  .emits_in_any_order()
                  .arg(buffer_of(pairs))
                  .arg(count_of(pairs));
    };
    if (PassSpec* cull = cull_orphans("orphan vf", "orphan vf candidates", l.orphans.vf.size(),
                                      "cs_cull_vertex_face_pairs", s.orphan_vf, s.kept_vf))
      cull->arg(buffer_of(start()))
          .arg(buffer_of(s.x1))
          .arg(value_of(separation))
          .arg(buffer_of(s.face_words))
          .arg(buffer_of(s.node_boxes));
    if (PassSpec* cull = cull_orphans("orphan ee", "orphan ee candidates", l.orphans.ee.size(), "cs_cull_edge_pairs",
                                      s.orphan_ee, s.kept_ee))
      cull->arg(buffer_of(s.edge_boxes));
  }

  void front_update(bool keep_front, const std::string& front_option, const GraphDevice& device)
  {
    using namespace runtime;
    auto& update = g.pass(keep_front ? "front update" : "search from seeds",
                          {broad_phase_program, "cs_front_update", front_option + device.front_update_options})
                       .launch_over(s.front)
                       .read(s.node_boxes)
                       .write(s.searches_cut);
    if (device.bounded_loops) update.stop_if(s.searches_cut);
    // The next front is packed into the buffer of the one it came from. A front pair
    // mostly stays one pair (or becomes its children where the boxes start to overlap)
    // and finds at most about one triangle pair: what sizes the segments of the first
    // run from a whole front, before any run has planned them. (Four of each, as
    // before, more than doubled the device memory of the step after the first.)
    if (keep_front) update.emit(s.next_front, 1.5).hand_over(s.front, s.next_front);
    update.emit(s.triangle_pairs, 1)
        .arg(buffer_of(s.front))
        .arg(count_of(s.front))
        .arg(buffer_of(s.nodes))
        .arg(buffer_of(s.node_boxes))
        .arg(buffer_of(s.faces))
        .arg(param_of(s.level_cap))
        .arg(buffer_of(s.searches_cut));
  }

  // A triangle pair gives 0.2-0.7 vertex-face and 0.6-1.7 edge-edge candidates on the
  // five real steps: what sizes the segments of a first run. (Two of each, as before,
  // set cloth-ball's run peak, at its first step: 201 MiB, where a settled step
  // holds 192.)
  // On the H200 the decomposition takes 72 registers a work-item: seven groups of 128
  // fit on a compute unit where three of 256 do, 896 work-items against 768, and its
  // scattered reads wait less. A CPU runs a group's work-items one after another and
  // keeps the context's groups.
  void decomposition(const std::string& front_option, const GraphDevice& device)
  {
    using namespace runtime;
    g.pass("decompose", {broad_phase_program, "cs_decompose", front_option + device.decompose_options})
        .launch_over(s.triangle_pairs)
        .work_group(device.cpu ? 0 : 128)
        .emit(s.vf, 1)
        .emit(s.ee, 2)
        .arg(buffer_of(s.triangle_pairs))
        .arg(count_of(s.triangle_pairs))
        .arg(buffer_of(s.faces))
        .arg(buffer_of(s.face_edges))
        .arg(buffer_of(s.face_words))
        .arg(buffer_of(start()))
        .arg(buffer_of(s.x1))
        .arg(value_of(separation))
        .arg(value_of(float_above(solver.tolerance)));
  }

  // The broad phase's candidate streams, the orphans' where there are some.
  ContactStreams candidate_streams() const
  {
    ContactStreams out = {{s.vf, ContactKind::vertex_face}, {s.ee, ContactKind::edge_edge}};
    if (s.kept_vf != runtime::StreamId{}) out.emplace_back(s.kept_vf, ContactKind::vertex_face);
    if (s.kept_ee != runtime::StreamId{}) out.emplace_back(s.kept_ee, ContactKind::edge_edge);
    return out;
  }

  // The elementary tests of every candidate stream, each emitting its contacts.
  void elementary_tests(const GraphDevice& device)
  {
    TestInputs in;
    in.x0 = exact_input ? s.x0_double : s.x0;
    in.x1 = exact_input ? s.x1_double : s.x1;
    in.x0_float = s.x0;
    in.x1_float = s.x1;
    in.exact_floats = s.exact_floats;
    in.faces = s.faces;
    in.edges = s.edges;
    in.candidates = candidate_streams();
    s.vertex_object = g.fixed("vertex objects", 4, t.vertex_count);
    s.earliest_only = g.param("earliest only", 4);
    s.earliest = g.fixed("earliest toi", 4, l.slots.size());
    in.vertex_object = s.vertex_object;
    in.earliest_only = s.earliest_only;
    if (solver.solver == Solver::cubic) {
      in.earliest = s.earliest;
    } else {
      s.object_contacts = g.fixed("earliest contact found", 8, l.slots.size());
      in.object_contacts = s.object_contacts;
    }
    s.contacts = add_elementary_tests(g, in, solver, device, [this](std::size_t guess) { return sized(guess); });
  }

  // Proximity instead of the tests: the distance of every candidate pair, one pass over
  // every candidate stream (proximity.cl), in double where the solver's precision is.
  void close_pairs()
  {
    using namespace runtime;
    s.close_pairs = g.variable("close pairs", 16, sized(1024));
    const ContactStreams candidates = candidate_streams();
    auto& pass = g.pass("close pairs", {"ccd/proximity.cl", "cs_close_pairs", solver_build_options(solver)})
                     .emit(s.close_pairs)
                     .emits_in_any_order()
                     .expect_items(0.25);
    over_streams(pass, candidates, "the proximity query");
    pass.arg(buffer_of(exact_input ? s.x1_double : s.x1)).arg(buffer_of(s.faces)).arg(buffer_of(s.edges));
    real_arg(pass, options.dhat, solver.precision);
  }

  // The earliest time of impact per object, in the steps that report nothing else:
  // where the contacts come back, the host takes the minimum from them if asked
  // (Detector::earliest_toi), and the step is shorter by these launches. The cubic
  // test lowers the times itself (add_elementary_tests); after the conservative
  // refinement, an atomic minimum over the contacts does.
  void earliest_toi()
  {
    using namespace runtime;
    const char* earliest = "ccd/earliest.cl";
    const std::string time_options = "-DCS_REAL_DOUBLE=" + std::to_string(int(exact_input));
    g.pass("clear earliest toi", {earliest, "cs_clear_earliest", time_options})
        .launch_items(l.slots.size())
        .write(s.earliest)
        .only_while(s.earliest_only)
        .arg(value_of(cl_uint(l.slots.size())))
        .arg(buffer_of(s.earliest));
    if (solver.solver == Solver::cubic) return;
    auto& pass = g.pass("earliest toi", {earliest, "cs_earliest_toi", time_options})
                     .update(s.earliest)
                     .only_while(s.earliest_only);
    over_streams(pass, s.contacts, "the earliest time of impact");
    pass.arg(buffer_of(s.faces)).arg(buffer_of(s.edges)).arg(buffer_of(s.vertex_object)).arg(buffer_of(s.earliest));
  }
};

}  // namespace

double bounds_margin(const DetectorOptions& options)
{
  return options.detects == Detects::close_pairs ? options.dhat : options.solver.min_separation;
}

GraphDevice graph_device(const runtime::Context& context)
{
  GraphDevice on;
  on.refine_items = 8 * context.device().compute_units * context.work_group_size();
  on.work_group_size = context.work_group_size();
  on.cpu = context.device().kind == runtime::DeviceKind::cpu;
  on.bounded_loops = context.loop_trip_limit() != 0;
  // Capped registers let more work-items share a compute unit. On the H200 the front
  // update takes 38 registers a work-item, so six groups of 256 share an SM; capped at
  // 32, eight do: cloth-ball 0.338 -> 0.313 ms, n-body 0.455 -> 0.416. The
  // decomposition takes 72, seven groups of 128; capped at 64, eight: 0.225 -> 0.222,
  // 0.333 -> 0.322. Lower caps spill: at 24 the front update took 0.358 ms, at 48 the
  // decomposition 0.258 and 0.361 (BENCHMARKS.md).
  on.front_update_options = runtime::register_cap_option(context.device(), 32);
  on.decompose_options = runtime::register_cap_option(context.device(), 64);
  return on;
}

CcdGraph build_ccd_graph(const SceneLayout& layout, const DetectorOptions& options, std::size_t front_size,
                         const GraphDevice& device)
{
  if (options.solver.min_separation < 0) throw InputError("the minimum separation must not be negative");
  GraphBuilder b(layout, options);
  b.geometry_streams();
  RefitPlan refit = plan_refit(layout, device.work_group_size);
  b.bounds_and_refit(device.work_group_size, refit);
  b.out.refit_ranges = std::move(refit.ranges);
  if (layout.seeds.empty()) return std::move(b.out);
  b.broad_phase(front_size, device);
  if (options.detects == Detects::close_pairs) {
    b.close_pairs();
  } else {
    b.elementary_tests(device);
    b.earliest_toi();
  }
  return std::move(b.out);
}

}  // namespace cstreams
