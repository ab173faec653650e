#include "stream_args.hpp"

#include <cstreams/pipeline/ccd_graph.hpp>
#include <cstreams/errors.hpp>
#include <cstreams/geometry/float_bounds.hpp>
#include <cstreams/runtime/context.hpp>

#include <algorithm>

namespace cstreams {

namespace {

constexpr const char* broad_phase_program = "ccd/broad_phase.cl";

// Builds one scene's graph piece by piece; each step adds the streams and passes of
// one stage of the pipeline and leaves those a scene does not need unset.
struct GraphBuilder {
  GraphBuilder(const SceneLayout& layout, const DetectorOptions& options, const GraphDevice& device)
      : l(layout), solver(options.solver), options(options), t(layout.topology),
        exact_input(solver.precision == Precision::double_),
        exact_twins(exact_input || (options.detects == Detects::contacts && escalates(solver, device))),
        separation(float_above(bounds_margin(options)))
  {
  }

  const SceneLayout& l;
  const SolverOptions& solver;
  const DetectorOptions& options;
  const Topology& t;
  const bool exact_input;
  const bool exact_twins;  // positions in double beside the float ones: double precision, or escalation
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
    if (exact_twins) {
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
        .arg(value_of(cl_uint(l.depth > 0 ? 2 * (l.depth - 1) : 0)))
        .arg(value_of(cl_uint(options.front_climb_levels)))
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
    if (has(s.kept_vf)) out.emplace_back(s.kept_vf, ContactKind::vertex_face);
    if (has(s.kept_ee)) out.emplace_back(s.kept_ee, ContactKind::edge_edge);
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
    if (!exact_input) {
      in.x0_exact = s.x0_double;
      in.x1_exact = s.x1_double;
    }
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
    TestStreams tests = add_elementary_tests(g, in, solver, device, [this](std::size_t guess) { return sized(guess); });
    s.contacts = std::move(tests.contacts);
    s.escalated = tests.escalated;
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
  on.fp64 = context.device().fp64;
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
  GraphBuilder b(layout, options, device);
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
