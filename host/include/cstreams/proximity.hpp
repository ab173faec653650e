#pragma once
// Pairs of a configuration closer than a distance dhat (the active set of a barrier),
// as a proximity detector finds them (DetectorOptions::detects).
#include <cstreams/contacts.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace cstreams {

// Which features of a pair are closest, in ipc-toolkit's names and order.
enum class PointTriangleDistance : std::uint8_t { p_t0, p_t1, p_t2, p_e0, p_e1, p_e2, p_t };
enum class EdgeEdgeDistance : std::uint8_t {
  ea0_eb0, ea0_eb1, ea1_eb0, ea1_eb1,  // a vertex of each edge
  ea_eb0, ea_eb1,                      // edge a and a vertex of edge b
  ea0_eb, ea1_eb,                      // a vertex of edge a and edge b
  ea_eb                                // a point inside each edge
};

// What the closest features are, whatever the pair's kind.
enum class ClosestFeatures : std::uint8_t { point_triangle, edge_edge, point_edge, point_point };

// A vertex and a face, or two edges, closer than dhat.
struct ClosePair {
  ContactKind kind = ContactKind::vertex_face;
  std::uint32_t object_a = 0, object_b = 0;
  // Local to their objects: the vertex and the face (a row of the object's faces, or
  // past them a segment's or a point's degenerate face: ObjectDescription::segments), or
  // two edges (Topology::edges of the objects' faces, the smaller first within one
  // object).
  std::uint32_t a = 0, b = 0;
  // Their vertices, as Contact::v: the vertex then the face's three, or each edge's two
  // ascending.
  std::array<std::uint32_t, 4> v{};
  std::uint8_t type = 0;  // PointTriangleDistance or EdgeEdgeDistance, as the kind
  float distance = 0;     // Euclidean, rounded to nearest float

  PointTriangleDistance point_triangle_type() const { return PointTriangleDistance(type); }
  EdgeEdgeDistance edge_edge_type() const { return EdgeEdgeDistance(type); }
  ClosestFeatures closest() const;
};

// By kind, objects and feature ids: the order of Detector::close_pairs().
bool canonical_less(const ClosePair& x, const ClosePair& y);

}  // namespace cstreams
