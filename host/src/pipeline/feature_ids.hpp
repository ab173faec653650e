#pragma once
// Device feature ids (global over the scene's streams) in the host's terms: object
// indices and ids local to each object, as contacts and candidates report them.
#include <cstreams/contacts.hpp>
#include <cstreams/detector.hpp>
#include <cstreams/pipeline/ccd_graph.hpp>

#include <array>
#include <cstdint>

namespace cstreams {

class FeatureIds {
public:
  FeatureIds(const SceneLayout& layout, const SceneDescription& scene, Precision precision)
      : layout_(layout), scene_(scene), precision_(precision)
  {
  }

  // A vertex of object_a and a face of object_b, or an edge of object_a and an edge of
  // object_b with object_a <= object_b; ids local to their objects.
  struct LocalPair {
    std::uint32_t object_a, object_b, a, b;
  };
  LocalPair local(ContactKind kind, std::uint32_t a, std::uint32_t b) const;

  // A contact as the device emits it: (feature a, feature b, time bits).
  Contact contact(ContactKind kind, const std::array<std::uint32_t, 4>& found) const;

private:
  const ObjectSlot& slot(std::uint32_t object) const { return layout_.slots[layout_.slot_of[object]]; }
  std::uint32_t object_of_vertex(std::uint32_t v) const { return layout_.vertex_object[v]; }
  std::uint32_t object_of_face(std::uint32_t f) const { return object_of_vertex(layout_.topology.faces[f][0]); }
  std::uint32_t object_of_edge(std::uint32_t e) const { return object_of_vertex(layout_.topology.edges[e][0]); }

  const SceneLayout& layout_;
  const SceneDescription& scene_;
  Precision precision_;
};

}  // namespace cstreams
