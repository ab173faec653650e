#pragma once
// A stream's buffer: allocated at a size (from the step arena for a stream emitted anew
// each run, while a run uses the arena), dropped, and grown with slack up to the
// stream's limit, a gathered stream keeping the items of earlier slices; and the view of
// the streams' state and specs that the scheduler's parts share. Owns how a buffer
// changes size; not when (the parts decide) nor what goes to make room (Scratch's
// with_memory wraps the calls that may). Private to the runtime.
#include "states.hpp"

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class Context;
class StepArena;
class Timeline;

class StreamBuffers {
public:
  StreamBuffers(Context& context, const StreamGraph& graph, StepArena& arena, std::vector<StreamState>& streams,
                Timeline* timeline)
      : context_(context), graph_(graph), arena_(arena), streams_(streams), timeline_(timeline)
  {
  }

  StreamState& state(StreamId s) { return streams_.at(s.index); }
  const StreamState& state(StreamId s) const { return streams_.at(s.index); }
  const StreamSpec& spec(StreamId s) const { return graph_.stream(s); }
  std::size_t words(StreamId s) const { return spec(s).element_bytes / 4; }
  std::vector<StreamState>& all() { return streams_; }

  // Within a run that uses the step arena, transient streams' buffers come from it.
  void set_from_arena(bool from_arena) { from_arena_ = from_arena; }
  // In a sliced run, the slices after the one running.
  void set_slices_left(std::size_t slices) { slices_left_ = slices; }

  // Throws StreamLimitExceeded past the stream's limit. A transient stream's buffer
  // comes from the arena where it is in use, its old items going first; otherwise the
  // old buffer stays until the new one is allocated.
  void allocate(StreamId s, std::size_t items);
  void drop(StreamState& st);
  // Grows a variable stream to hold `needed` items, with slack up to its limit (a
  // gathered stream's counting on the slices left yielding as many as this one).
  // Its producer runs again, so the old buffer goes first: the device need not hold both.
  void grow(StreamId s, std::size_t needed, bool slack = true);
  // The items grow() with slack takes for `needed`.
  std::size_t grown_items(StreamId s, std::size_t needed) const;

private:
  void grow_gathered(StreamId s, std::size_t needed, bool slack);

  Context& context_;
  const StreamGraph& graph_;
  StepArena& arena_;
  std::vector<StreamState>& streams_;
  Timeline* timeline_;  // profiling, or none
  bool from_arena_ = false;
  std::size_t slices_left_ = 0;
};

}  // namespace cstreams::runtime
