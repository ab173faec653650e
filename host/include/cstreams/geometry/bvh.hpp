#pragma once
#include <cstreams/geometry/mesh.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace cstreams {

// An 18-DOP: the slab [lo[k], hi[k]] of a set along each of nine axes, the three
// coordinate axes and the six face diagonals (x+y, x-y, y+z, y-z, z+x, z-x).
struct Kdop18 {
  std::array<double, 9> lo;
  std::array<double, 9> hi;

  static Kdop18 empty();
  void add(const Vec3& p);
  void merge(const Kdop18& other);
  // Grows every slab by `distance` in space (so by distance * |axis| in projection)
  // and by a rounding bound, making the box contain every point within `distance`.
  void inflate(double distance);
  bool overlaps(const Kdop18& other) const;
  Vec3 centre() const;  // of the axis-aligned part
};

// Projections of p onto the nine axes, each rounded outward so that the exact
// projection of the exact point lies within [lo, hi].
void project(const Vec3& p, std::array<double, 9>& lo, std::array<double, 9>& hi);

// The swept 18-DOP of a primitive moving linearly from x0 to x1: the 18-DOP of its
// corners at both ends, which contains every intermediate position because each is a
// convex combination of them.
Kdop18 swept_kdop(const Vec3* x0, const Vec3* x1, const std::uint32_t* vertices, int count, double separation);

// Swept BVs of every face, edge and vertex of a mesh over one step.
struct SweptBounds {
  std::vector<Kdop18> faces;
  std::vector<Kdop18> edges;
  std::vector<Kdop18> vertices;
};
struct Topology;
SweptBounds swept_bounds(const Topology& topology, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1,
                         double separation);

// A BVH over the faces of one mesh in a flat array, ready to upload: nodes are in
// breadth-first order (so children come after parents and each level is contiguous),
// the two children of an internal node are adjacent, and every leaf holds one face.
struct BvhNode {
  std::int32_t left = -1;      // first child; the second is left + 1; -1 for a leaf
  std::int32_t face = -1;      // the leaf's face; -1 for an internal node
  std::int32_t parent = -1;
};

struct Bvh {
  std::vector<BvhNode> nodes;
  std::vector<Kdop18> boxes;                 // per node
  std::vector<std::uint32_t> level_offsets;  // nodes of level d: [level_offsets[d], level_offsets[d+1])
  std::size_t depth() const { return level_offsets.empty() ? 0 : level_offsets.size() - 1; }

  // Recomputes every node's box from the faces' boxes, bottom-up.
  void refit(const std::vector<Kdop18>& face_boxes);
};

// Top-down build: each node splits its faces at the median along the longest axis of
// their centres' bounding box. The topology of the tree is kept from frame to frame;
// only refit() runs per step.
Bvh build_bvh(const std::vector<Kdop18>& face_boxes);

}  // namespace cstreams
