#pragma once
// Device feature ids (global over the scene's streams) in the host's terms: object
// indices and ids local to each object, as candidates report them (contacts get theirs
// on the device, contact_readback.hpp).
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>

#include <cstdint>

namespace cstreams {

class FeatureIds {
public:
  explicit FeatureIds(const SceneLayout& layout) : layout_(layout) {}

  // A vertex of object_a and a face of object_b, or an edge of object_a and an edge of
  // object_b with object_a <= object_b; ids local to their objects.
  struct LocalPair {
    std::uint32_t object_a, object_b, a, b;
  };
  LocalPair local(ContactKind kind, std::uint32_t a, std::uint32_t b) const;

private:
  const ObjectSlot& slot(std::uint32_t object) const { return layout_.slots[layout_.slot_of[object]]; }
  std::uint32_t object_of_vertex(std::uint32_t v) const { return layout_.vertex_object[v]; }
  std::uint32_t object_of_face(std::uint32_t f) const { return object_of_vertex(layout_.topology.faces[f][0]); }
  std::uint32_t object_of_edge(std::uint32_t e) const { return object_of_vertex(layout_.topology.edges[e][0]); }

  const SceneLayout& layout_;
};

}  // namespace cstreams
