#pragma once
#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace cstreams {

enum class ContactKind : std::uint8_t { vertex_face, edge_edge };

// One colliding feature pair. Vertex ids are local to their objects:
//   vertex-face: v[0] the vertex (of object_a), v[1..3] the face's vertices in face
//                order (of object_b);
//   edge-edge:   v[0], v[1] an edge of object_a and v[2], v[3] one of object_b, each
//                ascending; within one object the smaller edge comes first.
struct Contact {
  ContactKind kind = ContactKind::vertex_face;
  std::uint32_t object_a = 0;
  std::uint32_t object_b = 0;
  std::array<std::uint32_t, 4> v{};
  double toi = 1;

  // Identity of the feature pair, without the time.
  bool same_features(const Contact& o) const
  {
    return kind == o.kind && object_a == o.object_a && object_b == o.object_b && v == o.v;
  }
};

bool canonical_less(const Contact& a, const Contact& b);
// Sorts by kind, objects and vertex ids (then time), so lists from two devices or two
// runs compare with diff.
void sort_canonical(std::vector<Contact>& contacts);

// CSV: a header `kind,object_a,object_b,v0,v1,v2,v3,toi`, then one row per contact
// with kind `vf` or `ee` and the time printed exactly (17 significant digits).
void write_contacts_csv(std::ostream& out, const std::vector<Contact>& contacts);
void write_contacts_csv(const std::string& path, const std::vector<Contact>& contacts);

}  // namespace cstreams
