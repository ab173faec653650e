#include <cstreams/scenes/shapes.hpp>
#include <cstreams/geometry/topology.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <random>
#include <set>

using namespace cstreams;

namespace {

// Small meshes with boundaries, closed surfaces, several components and non-manifold
// fans, for the property tests.
std::vector<Mesh> test_meshes()
{
  std::vector<Mesh> meshes;
  meshes.push_back(scenes::sheet(1, 1, 1, 1));
  meshes.push_back(scenes::sheet(4, 3, 1, 1));
  meshes.push_back(scenes::icosphere(1, 1));
  Mesh two = scenes::icosphere(0, 1);
  scenes::append(two, scenes::sheet(3, 3, 2, 2));
  meshes.push_back(two);
  Mesh fan;  // three triangles on one edge: non-manifold
  fan.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1)};
  fan.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  meshes.push_back(fan);
  // A random soup: faces on random distinct vertices, sharing vertices in every way.
  std::mt19937 rng(5);
  Mesh soup;
  soup.positions.resize(12, Vec3::Zero());
  std::set<std::array<std::uint32_t, 3>> seen;
  while (soup.faces.size() < 30) {
    std::array<std::uint32_t, 3> f{std::uint32_t(rng() % 12), std::uint32_t(rng() % 12), std::uint32_t(rng() % 12)};
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) continue;
    auto key = f;
    std::sort(key.begin(), key.end());
    if (seen.insert(key).second) soup.faces.push_back(f);
  }
  meshes.push_back(soup);
  return meshes;
}

}  // namespace

TEST_CASE("edges are numbered as igl::edges numbers them", "[host][topology][quick]")
{
  for (const Mesh& m : test_meshes()) {
    const Topology t = build_topology(m.faces, m.positions.size());
    std::set<std::pair<std::uint32_t, std::uint32_t>> by_max_then_min;
    for (const Face& f : m.faces)
      for (int k = 0; k < 3; ++k) {
        const auto a = f[std::size_t(k)], b = f[std::size_t((k + 1) % 3)];
        by_max_then_min.insert({std::max(a, b), std::min(a, b)});
      }
    std::vector<Edge> expected;
    for (const auto& [hi, lo] : by_max_then_min) expected.push_back({lo, hi});
    CHECK(t.edges == expected);
    for (std::uint32_t f = 0; f < m.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Edge& e = t.edges[t.face_edges[f][std::size_t(k)]];
        const auto a = m.faces[f][std::size_t(k)], b = m.faces[f][std::size_t((k + 1) % 3)];
        CHECK(e == Edge{std::min(a, b), std::max(a, b)});
      }
  }
}

TEST_CASE("every feature has exactly one owner among its incident faces", "[host][topology][quick]")
{
  for (const Mesh& m : test_meshes()) {
    const Topology t = build_topology(m.faces, m.positions.size());
    std::vector<int> vertex_owners(t.vertex_count, 0), edge_owners(t.edges.size(), 0);
    for (std::uint32_t f = 0; f < t.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        if (t.owned[f] & (1u << k)) ++vertex_owners[t.faces[f][std::size_t(k)]];
        if (t.owned[f] & (8u << k)) ++edge_owners[t.face_edges[f][std::size_t(k)]];
      }
    for (std::uint32_t v = 0; v < t.vertex_count; ++v)
      CHECK(vertex_owners[v] == (t.vertex_owner[v] == no_index ? 0 : 1));
    for (int n : edge_owners) CHECK(n == 1);
  }
}

TEST_CASE("every feature pair without a shared vertex is tested exactly once", "[host][topology][quick]")
{
  for (const Mesh& m : test_meshes()) {
    const Topology t = build_topology(m.faces, m.positions.size());
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> vf_seen, ee_seen;
    // All non-adjacent triangle pairs, as the broad phase meets them when every BV overlaps.
    for (std::uint32_t a = 0; a < t.faces.size(); ++a)
      for (std::uint32_t b = a + 1; b < t.faces.size(); ++b) {
        if (t.adjacent(a, b)) continue;
        std::vector<VertexFace> ab, ba;
        std::vector<EdgeEdge> ee;
        decompose(t, a, t, b, ab, ba, ee);
        for (const auto& p : ab) ++vf_seen[{p.vertex, p.face}];
        for (const auto& p : ba) ++vf_seen[{p.vertex, p.face}];
        for (const auto& p : ee) ++ee_seen[{std::min(p.a, p.b), std::max(p.a, p.b)}];
      }
    const OrphanSet orphans = build_orphans(t);
    for (const auto& p : orphans.vf) ++vf_seen[{p.vertex, p.face}];
    for (const auto& p : orphans.ee) ++ee_seen[{p.a, p.b}];

    std::size_t vf_expected = 0, ee_expected = 0;
    for (std::uint32_t v = 0; v < t.vertex_count; ++v) {
      if (t.vertex_owner[v] == no_index) continue;
      for (std::uint32_t f = 0; f < t.faces.size(); ++f) {
        if (t.face_has_vertex(f, v)) continue;
        ++vf_expected;
        CHECK(vf_seen[{v, f}] == 1);
      }
    }
    for (std::uint32_t e = 0; e < t.edges.size(); ++e)
      for (std::uint32_t d = e + 1; d < t.edges.size(); ++d) {
        if (t.edges_share_vertex(e, d)) continue;
        ++ee_expected;
        CHECK(ee_seen[{e, d}] == 1);
      }
    // Nothing else was produced: in particular no pair that shares a vertex.
    CHECK(vf_seen.size() == vf_expected);
    CHECK(ee_seen.size() == ee_expected);
  }
}

TEST_CASE("connected components split a mesh and renumber it", "[host][topology][quick]")
{
  Mesh two = scenes::icosphere(0, 1);
  scenes::append(two, scenes::sheet(2, 1, 1, 1));
  two.positions.emplace_back(9, 9, 9);  // on no face: dropped
  const auto parts = connected_components(two.faces, two.positions.size());
  REQUIRE(parts.size() == 2);
  CHECK(parts[0].faces.size() == 20);
  CHECK(parts[0].vertices.size() == 12);
  CHECK(parts[1].faces.size() == 4);
  CHECK(parts[1].vertices.front() == 12);
  for (std::size_t f = 0; f < parts[1].faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      CHECK(parts[1].vertices[parts[1].faces[f][std::size_t(k)]] == two.faces[20 + f][std::size_t(k)]);
}
