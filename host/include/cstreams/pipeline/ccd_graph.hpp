#pragma once
// The CCD stream graph of a scene laid out in streams (scene_layout.hpp): which passes
// and streams a step needs, built without a device.
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/scene_layout.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace cstreams::runtime {
class Context;
}

namespace cstreams {

// The streams of the CCD graph; those a scene does not need stay unset.
struct CcdStreams {
  runtime::StreamId x0, x1, x0_double, x1_double;
  // The ends of the step after the next, and its starts where those are given too,
  // uploaded ahead (Detector::upload_ahead): no pass reads them, and they hold nothing
  // until the first such upload.
  runtime::StreamId x_next, x_next_double, x0_next, x0_next_double;
  runtime::StreamId faces, edges, nodes, face_edges, vertex_object;
  runtime::StreamId face_words;  // per face: the leaf holding its box << face_leaf_shift | Topology::owned
  runtime::StreamId edge_boxes, node_boxes, refit_ranges;  // a vertex's box is made where it is read
  runtime::StreamId front, next_front;  // variable (front kept) or front fixed: the seeds
  runtime::StreamId searches_cut;       // cs_front_update's cut[2]: a search ran out of loop trips
  runtime::StreamId triangle_pairs, vf, ee, orphan_vf, orphan_ee, kept_vf, kept_ee;
  runtime::StreamId earliest;
  runtime::StreamId object_contacts;  // refine.cl's `found`: per object, the earliest contact so far
  runtime::StreamId close_pairs;  // proximity.cl's (kind << 31 | a, b, distance bits, type)
  runtime::StreamId escalated;    // the float refinement's queries re-run in double (escalates())
  runtime::ParamId level_cap;
  runtime::ParamId earliest_only;     // 1: the step reports only each object's earliest time
  runtime::ParamId exact_floats;      // 1: the float positions are the input itself (no rounding)
  std::vector<std::pair<runtime::StreamId, ContactKind>> contacts;  // one per candidate stream
};

// What the elementary tests read: positions (double ones in double precision),
// topology, and the candidate streams with their kinds. In double precision, float
// positions rounded to nearest (where there are some) let the conservative solver
// screen in float first. Float positions are bounded as within half an ulp of the input
// unless the 4-byte exact_floats is nonzero: the input was floats, and the bounds are
// far tighter.
struct TestInputs {
  runtime::StreamId x0, x1, faces, edges;
  runtime::StreamId x0_float, x1_float;
  // In single precision, the positions in double where the solver escalates
  // (escalates()): the queries a float refinement cannot decide run again on them.
  runtime::StreamId x0_exact, x1_exact;
  runtime::ParamId exact_floats;
  std::vector<std::pair<runtime::StreamId, ContactKind>> candidates;
  // A scene of objects: every vertex's object, and a 4-byte parameter. Where the
  // parameter is nonzero, the step reports only each object's earliest time: the
  // conservative refinement gives up the queries that cannot hold one, keeping two
  // words per object (object_contacts, refine.cl), and the cubic test lowers each
  // object's time (earliest, a word per object) and skips the pairs that cannot lower
  // it (narrow_phase_pairs.cl). Unset where pairs belong to no objects.
  runtime::StreamId vertex_object, object_contacts, earliest;
  runtime::ParamId earliest_only;
};

// The arguments a kernel over one stream of candidate pairs starts with
// (cs_filter_flags in narrow_phase_pairs.cl): the pairs, their count, their kind,
// positions, topology, exactness. Kernels over every candidate stream at once take
// four (pairs, count, kind) triples instead (add_elementary_tests).
runtime::PassSpec& pair_kernel_args(runtime::PassSpec& pass, const TestInputs& inputs, runtime::StreamId pairs,
                                    ContactKind kind, Precision precision);
// A length or tolerance as a kernel of this precision takes it: in float, rounded up.
runtime::PassSpec& real_arg(runtime::PassSpec& pass, double x, Precision precision);

// What the graph takes from the device it runs on.
struct GraphDevice {
  std::size_t refine_items = 1 << 14;  // work-items of the conservative solver's refinement
                                       // rounds: enough work-groups to fill the device
  std::size_t work_group_size = 256;   // the scheduler's work-group size (its launches')
  bool fp64 = false;                   // the device has double precision
  bool cpu = false;                    // a CPU: the refinement keeps each query's function in
                                       // its state rather than making it again for each box
  bool bounded_loops = false;          // the device ends loops early: the front update stops
                                       // the run when a search ran out of loop trips (RunStopped)
  // Build options of the front update's and the decomposition's programs beyond the
  // scene's: register caps where the device's compiler takes them (graph_device()).
  std::string front_update_options, decompose_options;
};

// What the graph takes from the device of `context`.
GraphDevice graph_device(const runtime::Context& context);

// Whether the conservative solver in single precision sends the contacts its float
// enclosures cannot prove (an exact zero, no later than twice the time it reports) to
// a second refinement in double: SolverOptions::escalate, without a minimum separation
// (a contact then needs no zero, and float's rounding only blurs the separation by
// ulps), on a device with double.
bool escalates(const SolverOptions& solver, const GraphDevice& device);

// The streams the elementary tests emit: contacts, with their kinds, and the queries
// escalated to double (unset where the solver does not escalate).
struct TestStreams {
  std::vector<std::pair<runtime::StreamId, ContactKind>> contacts;
  runtime::StreamId escalated;
};

// Adds the elementary tests of every candidate stream to a graph. The cubic solver is
// one pass. The conservative one is a screen (the whole-domain bounds, then the
// filter), then breadth-first refinement across the device: a work list of (query, box)
// items whose rounds launch the device's refine_items work-items; where it escalates,
// a second refinement in double over the queries the first leaves undecided, on
// inputs.x0_exact and x1_exact. `sized` gives a variable stream's first capacity from a
// guess. With mark_limits, a contact that only a solver limit reported carries its time
// negated (for reports that count limits).
TestStreams add_elementary_tests(
    runtime::StreamGraph& g, const TestInputs& inputs, const SolverOptions& solver, const GraphDevice& device,
    const std::function<std::size_t(std::size_t)>& sized, bool mark_limits = false);

// How far the broad phase's boxes reach beyond their features: the minimum separation
// of a contact, or a proximity query's dhat.
double bounds_margin(const DetectorOptions& options);

struct CcdGraph {
  runtime::StreamGraph graph;
  CcdStreams streams;
  std::vector<std::array<std::uint32_t, 2>> refit_ranges;  // RefitPlan::ranges, for upload_scene
};

// The CCD stream graph of one scene: swept bounds and refit for moving objects only,
// the front update (or search from fixed seeds), the decomposition, the orphan culls
// for self-colliding objects, the elementary tests, and the earliest time per object.
// A proximity query's graph sweeps from the end positions to themselves and ends with
// the distances of the candidate pairs instead of the tests.
CcdGraph build_ccd_graph(const SceneLayout& layout, const DetectorOptions& options, std::size_t front_size,
                         const GraphDevice& device = {});

}  // namespace cstreams
