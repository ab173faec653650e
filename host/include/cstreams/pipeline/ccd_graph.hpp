#pragma once
// The pieces of the Detector that need no device: where each object lives in the
// scene's device streams, the initial BVTT front, and the CCD stream graph.
#include <cstreams/geometry/bvh.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/runtime/stream_graph.hpp>
#include <cstreams/geometry/topology.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace cstreams::runtime {
class Context;
}

namespace cstreams {

// One object's place in the scene's streams.
struct ObjectSlot {
  std::uint32_t object = 0;  // index in the SceneDescription
  bool moving = false;       // not static: refit every step
  bool self = false;         // collides with itself
  std::uint32_t first_vertex = 0, first_face = 0, first_edge = 0;
  std::uint32_t first_node = 0;  // static objects: their tree's nodes start here, in tree order
  std::int32_t root = -1;        // -1 for an object without faces
};

using NodePair = std::array<std::int32_t, 2>;

// A face's word on the device holds its BVH leaf above Topology::owned's six bits
// (CS_FACE_LEAF_SHIFT in cl_kernels/ccd/bounds.h): a scene's trees have fewer nodes
// than 2^26, about 33 million faces.
constexpr unsigned face_leaf_shift = 6;
constexpr std::size_t max_scene_nodes = std::size_t(1) << (32 - face_leaf_shift);
// A node on the device holds its parent + 1 above this many bits of its depth
// (CS_NODE_DEPTH_BITS in cl_kernels/ccd/bounds.h), in one word with the scene's node
// count above.
constexpr unsigned node_depth_bits = 6;

// Every object's mesh and BVH in one index space: moving objects first, then static
// ones, each in scene order, so that per-step passes cover a prefix of every stream.
// The BVHs form one forest whose moving part is in breadth-first order across all
// moving trees (level d of every tree, then level d + 1), so one refit pass per level
// serves them all.
struct SceneLayout {
  std::vector<ObjectSlot> slots;
  std::vector<std::uint32_t> slot_of;  // per object
  Topology topology;                   // all objects, global ids
  std::vector<Bvh> trees;              // per object, local ids
  std::vector<std::array<std::int32_t, 4>> nodes;  // (first child, face, parent, depth), global ids
  std::vector<std::uint32_t> levels;   // moving nodes of level d: [levels[d], levels[d + 1])
  std::size_t moving_vertices = 0, moving_faces = 0, moving_edges = 0, moving_nodes = 0;
  std::size_t depth = 0;               // deepest tree's levels
  std::vector<NodePair> seeds;         // (root, root) of every pair of objects that may collide
  OrphanSet orphans;                   // of self-colliding objects, global ids
  std::vector<std::uint32_t> vertex_object;

  std::size_t vertex_count() const { return topology.vertex_count; }
  bool has_static() const { return moving_vertices < topology.vertex_count; }
};

// Checks the description (an InputError naming the object) and lays it out; each
// tree is built over the object's starting positions.
SceneLayout make_layout(const SceneDescription& scene, double separation);

// The seeds expanded breadth first, level by level, without bounds tests, until there
// are at least `target` pairs or only leaf pairs are left: a cut of the BVTT to start
// from, with work for every compute unit.
std::vector<NodePair> expand_front(const SceneLayout& layout, std::size_t target);
// The same from a given front (a cut of the BVTT), which stays a cut, and never past
// `most` pairs: the last level is then expanded only in part.
std::vector<NodePair> expand_front(const SceneLayout& layout, std::vector<NodePair> front, std::size_t target,
                                   std::size_t most);
// The same pairs with the ones near each other in `front` dealt to different
// work-groups of `group` pairs: consecutive pairs of an expanded front lie in one region
// of the trees, where a fold of cloth makes every pair's search long, and a work-group's
// search takes as long as its pairs' together (H200, cloth-ball searched from seeds:
// 1.59 -> 0.75 ms).
std::vector<NodePair> spread_over_groups(const std::vector<NodePair>& front, std::size_t group);

// The refit of the moving trees' boxes, in launches of a band of levels each, deepest
// first (cs_refit_levels): a band goes over `levels` levels from `top` up, one group a
// node of level top, and that group's nodes at level top + d are the range
// ranges[first_range + group * levels + d] (first, end). In breadth-first order the
// children of consecutive nodes are consecutive, so they are one range of each level.
struct RefitBand {
  std::size_t top = 0, levels = 0, first_range = 0;
};
struct RefitPlan {
  std::vector<RefitBand> bands;
  std::vector<std::array<std::uint32_t, 2>> ranges;
};
// As many levels a band as keep a group's deepest one within its `group` work-items
// where the tree is full; the top band, from the roots, up to four nodes a work-item.
RefitPlan plan_refit(const SceneLayout& layout, std::size_t group);

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

// Adds the elementary tests of every candidate stream to a graph and returns the
// contact streams they emit, with their kinds. The cubic solver is one pass. The
// conservative one is a screen (the whole-domain bounds, then the filter), then
// breadth-first refinement across the device: a work list of (query, box) items whose
// rounds launch the device's refine_items work-items. `sized` gives a variable stream's first
// capacity from a guess. With mark_limits, a contact that only a solver limit reported carries
// its time negated (for reports that count limits).
std::vector<std::pair<runtime::StreamId, ContactKind>> add_elementary_tests(
    runtime::StreamGraph& g, const TestInputs& inputs, const SolverOptions& solver, const GraphDevice& device,
    const std::function<std::size_t(std::size_t)>& sized, bool mark_limits = false);

struct CcdGraph {
  runtime::StreamGraph graph;
  CcdStreams streams;
  std::vector<std::array<std::uint32_t, 2>> refit_ranges;  // RefitPlan::ranges, for upload_scene
};

// The CCD stream graph of one scene: swept bounds and refit for moving objects only,
// the front update (or search from fixed seeds), the decomposition, the orphan culls
// for self-colliding objects, the elementary tests, and the earliest time per object.
CcdGraph build_ccd_graph(const SceneLayout& layout, const DetectorOptions& options, std::size_t front_size,
                         const GraphDevice& device = {});

}  // namespace cstreams
