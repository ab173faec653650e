#pragma once
#include <array>
#include <cstddef>
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

// Contacts held elsewhere, read in place. Detector::contacts() hands out the last
// step's where the device's read put them: valid until that detector's next detect()
// or its end. Copy them into a std::vector to keep them longer.
class ContactSpan {
public:
  ContactSpan() = default;
  ContactSpan(const Contact* data, std::size_t size) : data_(data), size_(size) {}
  ContactSpan(const std::vector<Contact>& contacts) : data_(contacts.data()), size_(contacts.size()) {}

  const Contact* data() const { return data_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const Contact* begin() const { return data_; }
  const Contact* end() const { return data_ + size_; }
  const Contact& operator[](std::size_t i) const { return data_[i]; }
  // A copy that the next step leaves alone.
  operator std::vector<Contact>() const { return {begin(), end()}; }

private:
  const Contact* data_ = nullptr;
  std::size_t size_ = 0;
};

bool canonical_less(const Contact& a, const Contact& b);
// Sorts by kind, objects and vertex ids (then time), so lists from two devices or two
// runs compare with diff.
void sort_canonical(std::vector<Contact>& contacts);

// CSV: a header `kind,object_a,object_b,v0,v1,v2,v3,toi`, then one row per contact
// with kind `vf` or `ee` and the time printed exactly (17 significant digits).
void write_contacts_csv(std::ostream& out, ContactSpan contacts);
void write_contacts_csv(const std::string& path, ContactSpan contacts);

}  // namespace cstreams
