#include "close_pair_readback.hpp"

#include <cstreams/runtime/context.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstring>

namespace cstreams {

namespace {

using Record = std::array<std::uint32_t, 4>;  // proximity.cl's (kind << 31 | a, b, distance bits, type)

ClosePair close_pair(const Record& r, const SceneLayout& layout, const FeatureIds& ids)
{
  ClosePair c;
  c.kind = r[0] >> 31 ? ContactKind::edge_edge : ContactKind::vertex_face;
  const std::uint32_t a = r[0] & 0x7fffffffu, b = r[1];
  std::memcpy(&c.distance, &r[2], sizeof c.distance);
  c.type = std::uint8_t(r[3]);
  const FeatureIds::LocalPair l = ids.local(c.kind, a, b);
  c.object_a = l.object_a;
  c.object_b = l.object_b;
  c.a = l.a;
  c.b = l.b;
  const Topology& t = layout.topology;
  const ObjectSlot &slot_a = layout.slots[layout.slot_of[l.object_a]], &slot_b = layout.slots[layout.slot_of[l.object_b]];
  const std::uint32_t first_a = slot_a.first_vertex, first_b = slot_b.first_vertex;
  if (c.kind == ContactKind::vertex_face) {
    const Face& face = t.faces[b];
    c.v = {a - first_a, face[0] - first_b, face[1] - first_b, face[2] - first_b};
    return c;
  }
  const Edge& ea = t.edges[slot_a.first_edge + l.a];
  const Edge& eb = t.edges[slot_b.first_edge + l.b];
  c.v = {std::min(ea[0], ea[1]) - first_a, std::max(ea[0], ea[1]) - first_a, std::min(eb[0], eb[1]) - first_b,
         std::max(eb[0], eb[1]) - first_b};
  return c;
}

}  // namespace

void ClosePairReadback::read(const runtime::Scheduler& scheduler, runtime::StreamId close_pairs, bool profile,
                             runtime::PassStats& stats, std::vector<ClosePair>& out)
{
  stats = runtime::PassStats{};
  stats.name = "canonical close pairs";
  const std::size_t n = scheduler.count(close_pairs);
  out.resize(n);
  if (n == 0) return;
  // On the device: sorting 545,592 pairs of cloth-ball (dhat 1e-3 of its diagonal) on
  // the H200's host took 17 ms a call, and a radix sort of their keys there 30.
  runtime::Timeline timeline;
  const std::uint64_t launches = context_.kernel_launches();
  const runtime::Buffer& sorted = sorter_.sort(scheduler.buffer(close_pairs), n, profile ? &timeline : nullptr, stats.name.c_str());
  stats.launches = unsigned(context_.kernel_launches() - launches);
  runtime::ensure_capacity(context_, records_, n * sizeof(Record), "close pairs");
  context_.read(sorted, records_.data(), n * sizeof(Record));
  for (const auto& e : timeline.resolve()) stats.device_ns += e.nanoseconds;
  const Record* records = static_cast<const Record*>(records_.data());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = close_pair(records[i], layout_, ids_);
  });
  // Global ids order the pairs of one object canonically, not always those of several.
  const auto less = [](const ClosePair& x, const ClosePair& y) { return canonical_less(x, y); };
  if (layout_.slots.size() > 1 && !std::is_sorted(out.begin(), out.end(), less))
    tbb::parallel_sort(out.begin(), out.end(), less);
}

}  // namespace cstreams
