#pragma once
// The proximity oracle: every vertex-face and edge-edge pair of a mesh, no broad phase,
// distances in long double by a method of its own (projection where the foot falls
// inside a feature, else the least over its boundary), and which features are closest.
#include <cstreams/geometry/mesh.hpp>
#include <cstreams/proximity.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <tuple>
#include <vector>

namespace cstreams::test {

using Point = std::array<long double, 3>;

inline Point point(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
inline Point minus(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline long double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point cross(const Point& a, const Point& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline long double norm(const Point& a) { return std::sqrt(dot(a, a)); }

// Distance and the type code of proximity.hpp's enums; `runner_up` the least distance
// of any other type, which tells how clear the type is.
struct Closest {
  long double distance = INFINITY, runner_up = INFINITY;
  int type = -1;
  void offer(long double d, int t)
  {
    if (t == type) {
      distance = std::min(distance, d);
    } else if (d < distance) {
      runner_up = distance;
      distance = d;
      type = t;
    } else {
      runner_up = std::min(runner_up, d);
    }
  }
};

// p to the segment ab: the distance, and 0 or 1 where the foot is that end, else -1.
inline std::pair<long double, int> point_segment(const Point& p, const Point& a, const Point& b)
{
  const Point d = minus(b, a);
  const long double len2 = dot(d, d), s = len2 > 0 ? dot(minus(p, a), d) / len2 : 0;
  if (s <= 0) return {norm(minus(p, a)), 0};
  if (s >= 1) return {norm(minus(p, b)), 1};
  return {norm(cross(minus(p, a), d)) / std::sqrt(len2), -1};
}

inline Closest point_triangle(const Point& p, const Point& a, const Point& b, const Point& c)
{
  Closest out;
  const Point t[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const auto [d, end] = point_segment(p, t[k], t[(k + 1) % 3]);
    out.offer(d, end < 0 ? 3 + k : (k + end) % 3);
  }
  const Point n = cross(minus(b, a), minus(c, a));
  if (dot(n, n) > 0) {
    bool inside = true;
    for (int k = 0; k < 3; ++k) inside &= dot(cross(minus(t[(k + 1) % 3], t[k]), minus(p, t[k])), n) > 0;
    if (inside) out.offer(std::fabs(dot(minus(p, a), n)) / norm(n), 6);
  }
  return out;
}

inline Closest edge_edge(const Point& a0, const Point& a1, const Point& b0, const Point& b1)
{
  Closest out;
  const Point a[2] = {a0, a1}, b[2] = {b0, b1};
  for (int i = 0; i < 2; ++i) {
    const auto [da, ea] = point_segment(a[i], b0, b1);
    out.offer(da, ea < 0 ? 6 + i : 2 * i + ea);
    const auto [db, eb] = point_segment(b[i], a0, a1);
    out.offer(db, eb < 0 ? 4 + i : 2 * eb + i);
  }
  const Point d1 = minus(a1, a0), d2 = minus(b1, b0), n = cross(d1, d2);
  if (dot(n, n) > 0) {
    // The lines' closest points: where both fall inside, they are the edges'.
    const Point r = minus(b0, a0);
    const long double nn = dot(n, n), s = dot(cross(r, d2), n) / nn, t = dot(cross(r, d1), n) / nn;
    if (s > 0 && s < 1 && t > 0 && t < 1) out.offer(std::fabs(dot(r, n)) / std::sqrt(nn), 8);
  }
  return out;
}

// A pair as both sides name it: vertex and face, or the two edges' vertices, each
// edge ascending and the smaller edge first.
using PairKey = std::tuple<int, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;

inline PairKey key(const ClosePair& p)
{
  if (p.kind == ContactKind::vertex_face) return {0, p.a, p.b, 0, 0};
  std::array<std::uint32_t, 2> x{p.v[0], p.v[1]}, y{p.v[2], p.v[3]};
  if (y < x) std::swap(x, y);
  return {1, x[0], x[1], y[0], y[1]};
}

// The pair's type as the key names its features: an edge-edge pair whose edges the key
// takes the other way round has its edges' roles exchanged.
inline int key_type(const ClosePair& p)
{
  const int t = p.type;
  if (p.kind == ContactKind::vertex_face) return t;
  const std::array<std::uint32_t, 2> x{p.v[0], p.v[1]}, y{p.v[2], p.v[3]};
  if (!(y < x)) return t;
  constexpr int exchanged[9] = {0, 2, 1, 3, 6, 7, 4, 5, 8};
  return exchanged[t];
}

// Every pair closer than `reach`, with its distance and type.
inline std::map<PairKey, Closest> oracle_pairs(const Mesh& m, long double reach)
{
  std::map<PairKey, Closest> out;
  std::set<std::array<std::uint32_t, 2>> edge_set;
  for (const Face& f : m.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] != f[(k + 1) % 3]) edge_set.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
  const std::vector<std::array<std::uint32_t, 2>> edges(edge_set.begin(), edge_set.end());
  for (std::uint32_t v = 0; v < m.positions.size(); ++v)
    for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
      const Face& t = m.faces[f];
      if (t[0] == v || t[1] == v || t[2] == v) continue;
      const Closest c = point_triangle(point(m.positions[v]), point(m.positions[t[0]]), point(m.positions[t[1]]),
                                       point(m.positions[t[2]]));
      if (c.distance < reach) out[{0, v, f, 0, 0}] = c;
    }
  for (std::size_t i = 0; i < edges.size(); ++i)
    for (std::size_t j = i + 1; j < edges.size(); ++j) {
      const auto &x = edges[i], &y = edges[j];
      if (x[0] == y[0] || x[0] == y[1] || x[1] == y[0] || x[1] == y[1]) continue;
      const Closest c = edge_edge(point(m.positions[x[0]]), point(m.positions[x[1]]), point(m.positions[y[0]]),
                                  point(m.positions[y[1]]));
      if (c.distance < reach) out[{1, x[0], x[1], y[0], y[1]}] = c;
    }
  return out;
}

}  // namespace cstreams::test
