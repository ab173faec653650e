#pragma once
#include <cstreams/bvh.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/topology.hpp>

#include <array>
#include <memory>
#include <vector>

namespace cstreams {

namespace runtime {
class Context;
}

// An 18-DOP in single precision, as the device keeps it (cl_kernels/ccd/bounds.h):
// conservative for the exact double positions it was computed from.
struct Kdop18f {
  std::array<float, 9> lo;
  std::array<float, 9> hi;
  friend bool operator==(const Kdop18f& a, const Kdop18f& b) { return a.lo == b.lo && a.hi == b.hi; }
  bool contains(const Kdop18& exact) const;
  bool overlaps(const Kdop18f& other) const;
};

// Swept single-precision bounds of one mesh over a step, and its BVH's node boxes.
struct FloatBounds {
  std::vector<Kdop18f> faces, edges, vertices, nodes;
};

// The host's twin of the device computation: the same float operations in the same
// order, so that it equals DeviceBvh's result bit for bit.
FloatBounds float_bounds(const Topology& topology, const Bvh& bvh, const std::vector<Vec3>& x0,
                         const std::vector<Vec3>& x1, float separation);

// The streams of one mesh's bounds graph (positions, topology, tree, boxes).
struct BoundsStreams {
  runtime::StreamId x0, x1, faces, edges, nodes, face_boxes, edge_boxes, vertex_boxes, node_boxes;
};
// Adds to `graph` the passes that compute one mesh's swept float bounds and refit its
// BVH level by level (see DeviceBvh), and returns their streams.
BoundsStreams add_bounds_passes(runtime::StreamGraph& graph, const Topology& topology, const Bvh& bvh,
                                float separation);
// Uploads what add_bounds_passes' graph needs once (faces, edges, tree layout).
void upload_topology(runtime::Scheduler& scheduler, const BoundsStreams& s, const Topology& topology, const Bvh& bvh);
// Rounds positions to float (an InputError for a non-finite or out-of-range one).
std::vector<float> to_float_positions(const std::vector<Vec3>& x);
// Checks a step's positions against the mesh and uploads them, rounded to float.
void upload_positions(runtime::Scheduler& scheduler, const BoundsStreams& s, const std::vector<Vec3>& x0,
                      const std::vector<Vec3>& x1, std::size_t vertex_count);
std::vector<Kdop18f> unpack_dops(const std::vector<float>& flat);

// One mesh's swept bounds and BVH refit on a device, as a stream graph: three bounds
// passes (faces, edges, vertices) and one in-place refit pass per BVH level, deepest
// first. The topology and the tree layout are uploaded once; each step uploads the
// positions (rounded to float) and runs the graph.
class DeviceBvh {
public:
  DeviceBvh(runtime::Context& context, const Topology& topology, const Bvh& bvh, float separation);
  ~DeviceBvh();

  void refit(const std::vector<Vec3>& x0, const std::vector<Vec3>& x1);
  FloatBounds download() const;
  const runtime::RunStats& stats() const;

private:
  BoundsStreams streams_;
  std::unique_ptr<runtime::Scheduler> scheduler_;
  std::size_t vertex_count_;
};

}  // namespace cstreams
