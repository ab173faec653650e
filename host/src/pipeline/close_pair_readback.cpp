#include "close_pair_readback.hpp"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstring>

namespace cstreams {

void read_close_pairs(runtime::Scheduler& scheduler, runtime::StreamId close_pairs, const SceneLayout& layout,
                      const FeatureIds& ids, std::vector<ClosePair>& out)
{
  using Record = std::array<std::uint32_t, 4>;  // proximity.cl's (kind and type, a, b, distance bits)
  const std::vector<Record> records = scheduler.download<Record>(close_pairs);
  out.resize(records.size());
  const Topology& t = layout.topology;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const Record& r = records[i];
    ClosePair& c = out[i];
    c.kind = r[0] >> 4 ? ContactKind::vertex_face : ContactKind::edge_edge;
    c.type = std::uint8_t(r[0] & 15u);
    std::memcpy(&c.distance, &r[3], sizeof c.distance);
    const FeatureIds::LocalPair l = ids.local(c.kind, r[1], r[2]);
    c.object_a = l.object_a;
    c.object_b = l.object_b;
    c.a = l.a;
    c.b = l.b;
    const std::uint32_t first_a = layout.slots[layout.slot_of[l.object_a]].first_vertex;
    const std::uint32_t first_b = layout.slots[layout.slot_of[l.object_b]].first_vertex;
    if (c.kind == ContactKind::vertex_face) {
      const auto& face = t.faces[r[2]];
      c.v = {r[1] - first_a, face[0] - first_b, face[1] - first_b, face[2] - first_b};
    } else {
      // ids.local puts the edge of the smaller object first, as here.
      const bool swapped = layout.vertex_object[t.edges[r[1]][0]] != l.object_a;
      const auto& ea = t.edges[swapped ? r[2] : r[1]];
      const auto& eb = t.edges[swapped ? r[1] : r[2]];
      c.v = {std::min(ea[0], ea[1]) - first_a, std::max(ea[0], ea[1]) - first_a, std::min(eb[0], eb[1]) - first_b,
             std::max(eb[0], eb[1]) - first_b};
      if (l.object_a == l.object_b && l.a > l.b) {
        std::swap(c.a, c.b);
        std::swap(c.v[0], c.v[2]);
        std::swap(c.v[1], c.v[3]);
      }
    }
  }
  tbb::parallel_sort(out.begin(), out.end(), [](const ClosePair& x, const ClosePair& y) { return canonical_less(x, y); });
}

}  // namespace cstreams
