#include <cstreams/proximity.hpp>

#include <tuple>

namespace cstreams {

ClosestFeatures ClosePair::closest() const
{
  if (kind == ContactKind::vertex_face) {
    const auto t = point_triangle_type();
    if (t == PointTriangleDistance::p_t) return ClosestFeatures::point_triangle;
    return t >= PointTriangleDistance::p_e0 ? ClosestFeatures::point_edge : ClosestFeatures::point_point;
  }
  const auto t = edge_edge_type();
  if (t == EdgeEdgeDistance::ea_eb) return ClosestFeatures::edge_edge;
  return t >= EdgeEdgeDistance::ea_eb0 ? ClosestFeatures::point_edge : ClosestFeatures::point_point;
}

bool canonical_less(const ClosePair& x, const ClosePair& y)
{
  return std::tie(x.kind, x.object_a, x.object_b, x.a, x.b) < std::tie(y.kind, y.object_a, y.object_b, y.a, y.b);
}

}  // namespace cstreams
