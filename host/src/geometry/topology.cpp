#include <cstreams/geometry/topology.hpp>

#include <algorithm>
#include <numeric>

namespace cstreams {

bool Topology::face_has_vertex(std::uint32_t f, std::uint32_t v) const
{
  const Face& face = faces[f];
  return face[0] == v || face[1] == v || face[2] == v;
}

bool Topology::adjacent(std::uint32_t f, std::uint32_t g) const
{
  const Face& a = faces[f];
  return face_has_vertex(g, a[0]) || face_has_vertex(g, a[1]) || face_has_vertex(g, a[2]);
}

bool Topology::edges_share_vertex(std::uint32_t e, std::uint32_t d) const
{
  return edges[e][0] == edges[d][0] || edges[e][0] == edges[d][1] || edges[e][1] == edges[d][0] ||
         edges[e][1] == edges[d][1];
}

std::vector<std::uint32_t> Topology::neighbours(std::uint32_t f) const
{
  std::vector<std::uint32_t> out;
  for (std::uint32_t v : faces[f])
    for (std::uint32_t i = vertex_face_offsets[v]; i < vertex_face_offsets[v + 1]; ++i)
      if (vertex_faces[i] != f) out.push_back(vertex_faces[i]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

Topology build_topology(const std::vector<Face>& faces, std::size_t vertex_count)
{
  Topology t;
  t.vertex_count = vertex_count;
  t.faces = faces;
  const std::size_t nf = faces.size();

  // Half-edges sorted the igl way; equal keys collapse into one edge.
  struct HalfEdge {
    std::uint32_t hi, lo, face, k;
  };
  // A degenerate face (a segment's (a, b, b) or a point's (p, p, p)) has no edge where
  // its two ends are one vertex.
  std::vector<HalfEdge> half;
  half.reserve(3 * nf);
  for (std::uint32_t f = 0; f < nf; ++f)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = faces[f][k], b = faces[f][(k + 1) % 3];
      if (a != b) half.push_back({std::max(a, b), std::min(a, b), f, k});
    }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.hi != y.hi ? x.hi < y.hi : x.lo != y.lo ? x.lo < y.lo : x.face < y.face;
  });
  t.face_edges.assign(nf, {no_index, no_index, no_index});
  for (std::size_t i = 0; i < half.size(); ++i) {
    if (i == 0 || half[i].hi != half[i - 1].hi || half[i].lo != half[i - 1].lo) {
      t.edges.push_back({half[i].lo, half[i].hi});
      t.edge_owner.push_back(half[i].face);  // sorted by face within a key: the lowest
    }
    t.face_edges[half[i].face][half[i].k] = std::uint32_t(t.edges.size() - 1);
  }

  t.vertex_face_offsets.assign(vertex_count + 1, 0);
  for (const Face& f : faces)
    for (std::uint32_t v : f) ++t.vertex_face_offsets[v + 1];
  std::partial_sum(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end(), t.vertex_face_offsets.begin());
  t.vertex_faces.resize(3 * nf);
  std::vector<std::uint32_t> fill(t.vertex_face_offsets.begin(), t.vertex_face_offsets.end() - 1);
  for (std::uint32_t f = 0; f < nf; ++f)
    for (std::uint32_t v : faces[f]) t.vertex_faces[fill[v]++] = f;  // ascending f within each vertex

  t.vertex_owner.assign(vertex_count, no_index);
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (t.vertex_face_offsets[v + 1] > t.vertex_face_offsets[v]) t.vertex_owner[v] = t.vertex_faces[t.vertex_face_offsets[v]];

  t.owned.assign(nf, 0);
  // A vertex a face holds twice, or an edge it holds both ways (a segment's), is owned
  // in its first place only.
  for (std::uint32_t f = 0; f < nf; ++f)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t v = faces[f][k], e = t.face_edges[f][k];
      const bool first_v = k == 0 || (faces[f][0] != v && (k == 1 || faces[f][1] != v));
      const bool first_e = k == 0 || (t.face_edges[f][0] != e && (k == 1 || t.face_edges[f][1] != e));
      if (first_v && t.vertex_owner[v] == f) t.owned[f] |= std::uint8_t(1u << k);
      if (e != no_index && first_e && t.edge_owner[e] == f) t.owned[f] |= std::uint8_t(8u << k);
    }
  return t;
}

void decompose(const Topology& ta, std::uint32_t fa, const Topology& tb, std::uint32_t fb,
               std::vector<VertexFace>& vf_a_on_b, std::vector<VertexFace>& vf_b_on_a, std::vector<EdgeEdge>& ee)
{
  const std::uint8_t oa = ta.owned[fa], ob = tb.owned[fb];
  for (std::uint32_t k = 0; k < 3; ++k) {
    if (oa & (1u << k)) vf_a_on_b.push_back({ta.faces[fa][k], fb});
    if (ob & (1u << k)) vf_b_on_a.push_back({tb.faces[fb][k], fa});
  }
  for (std::uint32_t i = 0; i < 3; ++i) {
    if (!(oa & (8u << i))) continue;
    for (std::uint32_t j = 0; j < 3; ++j)
      if (ob & (8u << j)) ee.push_back({ta.face_edges[fa][i], tb.face_edges[fb][j]});
  }
}

OrphanSet build_orphans(const Topology& t)
{
  OrphanSet orphans;
  for (std::uint32_t f = 0; f < t.faces.size(); ++f) {
    const std::uint8_t of = t.owned[f];
    if (!of) continue;
    for (std::uint32_t g : t.neighbours(f)) {
      for (std::uint32_t k = 0; k < 3; ++k)
        if ((of & (1u << k)) && !t.face_has_vertex(g, t.faces[f][k])) orphans.vf.push_back({t.faces[f][k], g});
      if (g < f) continue;  // each unordered pair of owners once
      for (std::uint32_t i = 0; i < 3; ++i) {
        if (!(of & (8u << i))) continue;
        for (std::uint32_t j = 0; j < 3; ++j) {
          if (!(t.owned[g] & (8u << j))) continue;
          const std::uint32_t e = t.face_edges[f][i], d = t.face_edges[g][j];
          if (!t.edges_share_vertex(e, d)) orphans.ee.push_back({std::min(e, d), std::max(e, d)});
        }
      }
    }
  }
  std::sort(orphans.vf.begin(), orphans.vf.end());
  std::sort(orphans.ee.begin(), orphans.ee.end());
  return orphans;
}

std::vector<Component> connected_components(const std::vector<Face>& faces, std::size_t vertex_count)
{
  std::vector<std::uint32_t> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Face& f : faces)
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(f[0]), b = find(f[std::size_t(k)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<bool> used(vertex_count, false);
  for (const Face& f : faces)
    for (std::uint32_t v : f) used[v] = true;

  // Components are numbered by their smallest vertex, so the split is deterministic.
  std::vector<std::uint32_t> component_of_root(vertex_count, no_index);
  std::vector<Component> components;
  std::vector<std::uint32_t> local(vertex_count, no_index);
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (!used[v]) continue;
    const std::uint32_t r = find(v);
    if (component_of_root[r] == no_index) {
      component_of_root[r] = std::uint32_t(components.size());
      components.emplace_back();
    }
    auto& c = components[component_of_root[r]];
    local[v] = std::uint32_t(c.vertices.size());
    c.vertices.push_back(v);
  }
  for (const Face& f : faces)
    components[component_of_root[find(f[0])]].faces.push_back({local[f[0]], local[f[1]], local[f[2]]});
  return components;
}

}  // namespace cstreams
