#include "position_writes.hpp"

#include <algorithm>
#include <cstring>

namespace cstreams {

void* PositionWrites::stage(runtime::StreamId stream, std::size_t first, std::size_t count, std::size_t item_bytes)
{
  // Long done: the step that read them has returned its results.
  context_.block_until(queued_);
  queued_.clear();
  auto s = std::find_if(staged_.begin(), staged_.end(), [&](const Staged& x) { return x.stream == stream; });
  if (s == staged_.end()) s = staged_.insert(staged_.end(), Staged{stream, 0, {}, {}});
  const std::size_t bytes = count * item_bytes, offset = s->used;
  if (offset + bytes > s->memory.bytes()) {
    runtime::HostStaging grown(context_, std::max(offset + bytes, 2 * s->memory.bytes()), "positions given");
    if (offset) std::memcpy(grown.data(), s->memory.data(), offset);
    s->memory = std::move(grown);
  }
  s->used += bytes;
  uncommitted_.emplace_back(std::size_t(s - staged_.begin()), Run{first, count, offset});
  return static_cast<char*>(s->memory.data()) + offset;
}

void PositionWrites::commit()
{
  // A stream's staging grows in the order its runs come, so items adjacent in the
  // stream are adjacent there too, and a joined run keeps its first part's offset.
  for (const auto& [s, run] : uncommitted_) append_run(staged_[s].runs, run);
  uncommitted_.clear();
}

void PositionWrites::discard()
{
  // Staged in order, so each stream's first uncommitted run starts what is dropped.
  for (auto it = uncommitted_.rbegin(); it != uncommitted_.rend(); ++it) staged_[it->first].used = it->second.offset;
  uncommitted_.clear();
}

void PositionWrites::queue(runtime::Scheduler& scheduler)
{
  for (Staged& s : staged_) {
    for (const Run& r : s.runs)
      queued_.push_back(
          scheduler.write_queued(s.stream, r.first, static_cast<const char*>(s.memory.data()) + r.offset, r.count));
    s.runs.clear();
    s.used = 0;
  }
}

}  // namespace cstreams
