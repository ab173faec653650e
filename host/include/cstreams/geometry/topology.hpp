#pragma once
#include <cstreams/geometry/mesh.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace cstreams {

using Edge = std::array<std::uint32_t, 2>;  // (smaller, larger) vertex id
constexpr std::uint32_t no_index = 0xffffffffu;

// A vertex-face or edge-edge feature pair, by mesh-local ids.
struct VertexFace {
  std::uint32_t vertex;
  std::uint32_t face;
  friend bool operator==(VertexFace a, VertexFace b) { return a.vertex == b.vertex && a.face == b.face; }
  friend bool operator<(VertexFace a, VertexFace b) { return a.vertex != b.vertex ? a.vertex < b.vertex : a.face < b.face; }
};
struct EdgeEdge {
  std::uint32_t a;  // a < b within one mesh
  std::uint32_t b;
  friend bool operator==(EdgeEdge x, EdgeEdge y) { return x.a == y.a && x.b == y.b; }
  friend bool operator<(EdgeEdge x, EdgeEdge y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
};

// Connectivity of one triangle mesh, built once per object.
//
// Edges are numbered as libigl's igl::edges(F) numbers them (unique undirected edges
// sorted by larger then smaller end point), which is the convention of the
// ground-truth data. Face edge k joins face[k] and face[(k+1)%3].
//
// Feature ownership (the paper's representative triangles): every vertex and edge
// belongs to exactly one incident face, the lowest-numbered, so that a feature pair
// met through several triangle pairs is tested through one only.
struct Topology {
  std::size_t vertex_count = 0;
  std::vector<Face> faces;
  std::vector<Edge> edges;
  std::vector<std::array<std::uint32_t, 3>> face_edges;
  std::vector<std::uint32_t> vertex_owner;  // no_index for a vertex on no face
  std::vector<std::uint32_t> edge_owner;
  // Bits 0-2: face vertex k is owned by this face; bits 3-5: face edge k is.
  std::vector<std::uint8_t> owned;
  // Faces around each vertex, compressed: faces of v are
  // vertex_faces[vertex_face_offsets[v] .. vertex_face_offsets[v+1]).
  std::vector<std::uint32_t> vertex_face_offsets;
  std::vector<std::uint32_t> vertex_faces;

  bool face_has_vertex(std::uint32_t f, std::uint32_t v) const;
  // Two faces are adjacent when they share a vertex (and so maybe an edge).
  bool adjacent(std::uint32_t f, std::uint32_t g) const;
  bool edges_share_vertex(std::uint32_t e, std::uint32_t d) const;
  // Faces sharing a vertex with f, f excluded, ascending.
  std::vector<std::uint32_t> neighbours(std::uint32_t f) const;
};

Topology build_topology(const std::vector<Face>& faces, std::size_t vertex_count);

// Feature pairs that the triangle-pair decomposition never meets because their owners
// are adjacent (and adjacent triangles are never paired): every VF pair (v, g) with v
// owned by a face adjacent to g and v not on g, and every EE pair of edges with
// adjacent owners and no shared vertex. Built once per self-colliding object.
struct OrphanSet {
  std::vector<VertexFace> vf;
  std::vector<EdgeEdge> ee;
};
OrphanSet build_orphans(const Topology& topology);

// Feature pairs of one pair of triangles. Appends to `vf` the owned vertices of each
// face against the other face, and to `ee` the owned edges of one against the owned
// edges of the other; with `same_mesh`, the faces must be non-adjacent.
void decompose(const Topology& ta, std::uint32_t fa, const Topology& tb, std::uint32_t fb,
               std::vector<VertexFace>& vf_a_on_b, std::vector<VertexFace>& vf_b_on_a, std::vector<EdgeEdge>& ee);

// Splits a mesh into its connected components (faces joined through shared vertices).
// Returns, per component, the original vertex ids in ascending order and the faces
// renumbered to them; vertices on no face are dropped.
struct Component {
  std::vector<std::uint32_t> vertices;
  std::vector<Face> faces;
};
std::vector<Component> connected_components(const std::vector<Face>& faces, std::size_t vertex_count);

}  // namespace cstreams
