#include "feature_ids.hpp"

#include <algorithm>
#include <cstring>

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

Contact FeatureIds::contact(ContactKind kind, const std::array<std::uint32_t, 4>& c) const
{
  Contact out;
  out.kind = kind;
  if (precision_ == Precision::double_) {
    const std::uint64_t bits = std::uint64_t(c[2]) | std::uint64_t(c[3]) << 32;
    std::memcpy(&out.toi, &bits, sizeof bits);
  } else {
    float toi;
    std::memcpy(&toi, &c[2], sizeof toi);
    out.toi = toi;
  }
  const LocalPair p = local(kind, c[0], c[1]);
  out.object_a = p.object_a;
  out.object_b = p.object_b;
  if (kind == ContactKind::vertex_face) {
    const Face& f = scene_.objects[p.object_b].faces[p.b];
    out.v = {p.a, f[0], f[1], f[2]};
    return out;
  }
  auto edge = [&](std::uint32_t o, std::uint32_t e) {
    const ObjectSlot& sl = slot(o);
    const Edge& g = layout_.topology.edges[sl.first_edge + e];
    return Edge{g[0] - sl.first_vertex, g[1] - sl.first_vertex};
  };
  Edge a = edge(p.object_a, p.a), b = edge(p.object_b, p.b);
  if (p.object_a == p.object_b && b < a) std::swap(a, b);
  out.v = {a[0], a[1], b[0], b[1]};
  return out;
}

}  // namespace cstreams
