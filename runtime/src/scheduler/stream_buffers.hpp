#pragma once
// A stream's buffer: allocated at a size (from the step arena for a stream emitted anew
// each run, while a run uses the arena), dropped, and grown with slack up to the
// stream's limit, a gathered stream keeping the items of earlier slices. Owns how a
// buffer changes size; not when (the scheduler decides) nor what goes to make room (the
// scheduler's with_memory wraps the calls that may). Private to the runtime.
#include "states.hpp"

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class Context;
class StepArena;
class Timeline;

class StreamBuffers {
public:
  StreamBuffers(Context& context, const StreamGraph& graph, StepArena& arena, std::vector<StreamState>& streams)
      : context_(context), graph_(graph), arena_(arena), streams_(streams)
  {
  }

  // Throws StreamLimitExceeded past the stream's limit. A transient stream's buffer
  // comes from the arena where `from_arena`, its old items going first; otherwise the
  // old buffer stays until the new one is allocated.
  void allocate(StreamId s, std::size_t items, bool from_arena);
  void drop(StreamState& st);
  // Grows a variable stream to hold `needed` items, with slack up to its limit (a
  // gathered stream's counting on `slices_left` slices yielding as many as this one).
  // Its producer runs again, so the old buffer goes first: the device need not hold both.
  void grow(StreamId s, std::size_t needed, bool slack, bool from_arena, std::size_t slices_left, Timeline* timeline);

private:
  void grow_gathered(StreamId s, std::size_t needed, bool slack, bool from_arena, std::size_t slices_left,
                     Timeline* timeline);

  Context& context_;
  const StreamGraph& graph_;
  StepArena& arena_;
  std::vector<StreamState>& streams_;
};

}  // namespace cstreams::runtime
