#include "stream_buffers.hpp"

#include "../step_arena.hpp"
#include "growth.hpp"

#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/error.hpp>

#include <algorithm>

namespace cstreams::runtime {

void StreamBuffers::allocate(StreamId s, std::size_t items)
{
  auto& st = streams_.at(s.index);
  const StreamSpec& spec = graph_.stream(s);
  if (items > st.limit) throw StreamLimitExceeded(spec.name, items, st.limit);
  const std::size_t bytes = items * spec.element_bytes;
  if (from_arena_ && st.transient) {
    drop(st);
    st.buffer = arena_.take(bytes, spec.name.c_str(), st.arena_at);
  } else {
    Buffer fresh(context_, bytes, spec.name.c_str());
    arena_.give_back(st.arena_at);
    st.buffer = std::move(fresh);
  }
  st.capacity = items;
  st.peak_bytes = std::max(st.peak_bytes, st.buffer.bytes());
  st.spent = false;
}

void StreamBuffers::drop(StreamState& st)
{
  arena_.give_back(st.arena_at);
  st.buffer = Buffer();
  st.capacity = 0;
}

void StreamBuffers::grow(StreamId s, std::size_t needed, bool slack)
{
  auto& st = streams_.at(s.index);
  if (st.base > 0) return grow_gathered(s, needed, slack);
  drop(st);
  allocate(s, slack ? grown_items(s, needed) : needed);
}

std::size_t StreamBuffers::grown_items(StreamId s, std::size_t needed) const
{
  return std::min(grown(needed), std::max(streams_.at(s.index).limit, needed));
}

// Where the device cannot hold the items twice, they wait on the host.
void StreamBuffers::grow_gathered(StreamId s, std::size_t needed, bool slack)
{
  auto& st = streams_.at(s.index);
  const std::size_t element_bytes = graph_.stream(s).element_bytes, bytes = st.base * element_bytes;
  const std::size_t items =
      slack ? std::min(grown(needed + (needed - std::min(needed, st.base)) * slices_left_), std::max(st.limit, needed))
            : needed;
  Buffer kept = std::move(st.buffer);
  st.capacity = 0;
  try {
    allocate(s, items);
    context_.copy(kept, st.buffer, bytes, 0, 0, timeline_);
    return;
  } catch (const DeviceMemoryExhausted&) {
  }
  std::vector<unsigned char> waiting(bytes);
  const std::size_t kept_items = kept.bytes() / element_bytes;
  context_.read(kept, waiting.data(), bytes, 0, timeline_);
  kept = Buffer();
  try {
    allocate(s, items);
  } catch (const DeviceMemoryExhausted&) {
    // The memory just given back holds the items again: a caller that makes room
    // may grow the stream once more.
    allocate(s, kept_items);
    context_.write(st.buffer, waiting.data(), bytes);
    throw;
  }
  context_.write(st.buffer, waiting.data(), bytes);
}

}  // namespace cstreams::runtime
