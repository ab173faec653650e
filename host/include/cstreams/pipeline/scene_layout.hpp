#pragma once
// Where each object lives in the scene's device streams, the BVTT fronts a detector
// starts from, and the plan of the BVH refit: the pieces of the Detector that need no
// device and no stream graph.
#include <cstreams/detector.hpp>
#include <cstreams/geometry/bvh.hpp>
#include <cstreams/geometry/topology.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

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
  std::vector<std::uint32_t> node_object, node_local;  // per global node: its tree, and its index there
  std::vector<std::uint32_t> levels;   // moving nodes of level d: [levels[d], levels[d + 1])
  std::size_t moving_vertices = 0, moving_faces = 0, moving_edges = 0, moving_nodes = 0;
  std::size_t depth = 0;               // deepest tree's levels
  std::vector<NodePair> seeds;         // (root, root) of every pair of objects that may collide
  OrphanSet orphans;                   // of self-colliding objects, global ids
  std::vector<std::uint32_t> vertex_object;

  std::size_t vertex_count() const { return topology.vertex_count; }
  // A node's box at the starting positions (the one its tree was built over).
  const Kdop18& start_box(std::int32_t node) const
  {
    return trees[node_object[std::size_t(node)]].boxes[node_local[std::size_t(node)]];
  }
  bool has_static() const { return moving_vertices < topology.vertex_count; }
};

// Checks the description (an InputError naming the object) and lays it out; each
// tree is built over the object's starting positions.
// The faces an object collides with: its own, then a degenerate face for each segment,
// (a, b, b), and for each point, (p, p, p).
std::vector<Face> collision_faces(const ObjectDescription& object);

SceneLayout make_layout(const SceneDescription& scene, double separation);

// The seeds expanded breadth first, level by level, without bounds tests, until there
// are at least `target` pairs or only leaf pairs are left: a cut of the BVTT to start
// from, with work for every compute unit.
std::vector<NodePair> expand_front(const SceneLayout& layout, std::size_t target);
// The same from a given front (a cut of the BVTT), which stays a cut, and never past
// `most` pairs: the last level is then expanded only in part.
std::vector<NodePair> expand_front(const SceneLayout& layout, std::vector<NodePair> front, std::size_t target,
                                   std::size_t most);
// Each pair of the cut `front` replaced by the pairs below it down to `levels` levels,
// in the same order, except that pairs of distinct nodes whose boxes at the starting
// positions are apart stay as they are: a finer cut that deepens only where the starting
// positions' exact front lies, and so holds no more pairs than that front, where an
// untested expansion of objects far apart would hold mostly pairs far apart.
std::vector<NodePair> expand_overlapping(const SceneLayout& layout, const std::vector<NodePair>& front,
                                         unsigned levels);
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

}  // namespace cstreams
