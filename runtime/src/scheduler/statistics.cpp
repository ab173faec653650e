#include "statistics.hpp"

#include "../step_arena.hpp"

#include <algorithm>
#include <map>
#include <string>

namespace cstreams::runtime {

void collect_stats(RunStats& stats, const RunFigures& figures)
{
  std::map<std::string, std::uint64_t> by_label;
  stats.commands = figures.timeline.resolve();
  for (const auto& e : stats.commands) by_label[e.label] += e.nanoseconds;
  std::uint64_t pass_total = 0;
  // Segments are shared between stages: the run's total counts each buffer once, and
  // once the run is over they are all idle.
  stats.scratch_bytes = figures.shared_scratch_bytes;
  for (const auto& idle : figures.idle_segments) stats.segment_bytes += idle.bytes();
  // The arena, less the transient streams that it holds (counted as theirs).
  std::size_t in_streams = 0;
  for (const auto& st : figures.streams)
    if (st.arena_at != StepArena::none && st.arena_at + st.buffer.bytes() <= figures.arena.bytes())
      in_streams += st.buffer.bytes();
  stats.segment_bytes += figures.arena.bytes() - in_streams;
  for (auto& p : figures.passes) {
    p.stats.device_ns = by_label[p.spec->name];
    pass_total += p.stats.device_ns;
    p.stats.scratch_bytes = p.keep.bytes();
    const std::size_t list_bytes =
        p.list ? p.list->state.bytes() + p.list->lists[0].bytes() + p.list->lists[1].bytes() : 0;
    p.stats.scratch_bytes += list_bytes;
    for (const auto& e : p.emitters) {
      p.stats.scratch_bytes += e.counts.bytes() + e.offsets.bytes() + e.plan.bytes();
      p.stats.segment_bytes += e.segment_bytes;
    }
    stats.scratch_bytes += p.stats.scratch_bytes;
    p.stats.scratch_bytes += p.stats.segment_bytes;
    // A work list taken from the arena went back with its stage, into the arena's bytes:
    // the pass reports what it held.
    if (p.list) p.stats.scratch_bytes += p.list->held_bytes - std::min(p.list->held_bytes, list_bytes);
    stats.passes.push_back(p.stats);
  }
  stats.scratch_bytes += stats.segment_bytes;
  std::uint64_t all = 0;
  for (const auto& [label, ns] : by_label) all += ns;
  stats.scheduler_ns = all - pass_total;
  std::vector<StreamState>& streams = figures.streams;
  for (std::size_t i = 0; i < streams.size(); ++i) {
    const auto& sp = figures.graph.streams()[i];
    streams[i].run_items = streams[i].earlier + streams[i].count;
    stats.streams.push_back({sp.name, sp.variable, streams[i].count, streams[i].capacity, streams[i].buffer.bytes(),
                             streams[i].peak_bytes, streams[i].run_items});
  }
}

}  // namespace cstreams::runtime
