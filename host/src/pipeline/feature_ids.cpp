#include "feature_ids.hpp"

#include <algorithm>

namespace cstreams {

FeatureIds::LocalPair FeatureIds::local(ContactKind kind, std::uint32_t a, std::uint32_t b) const
{
  if (kind == ContactKind::vertex_face) {
    const std::uint32_t oa = object_of_vertex(a), ob = object_of_face(b);
    return {oa, ob, a - slot(oa).first_vertex, b - slot(ob).first_face};
  }
  std::uint32_t oa = object_of_edge(a), ob = object_of_edge(b);
  if (oa > ob) {
    std::swap(oa, ob);
    std::swap(a, b);
  }
  return {oa, ob, a - slot(oa).first_edge, b - slot(ob).first_edge};
}

}  // namespace cstreams
