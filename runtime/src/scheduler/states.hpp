#pragma once
// What the scheduler keeps of each stream, emitted stream and pass between and within
// runs. Plain state: the parts of the scheduler (runtime/src/scheduler/) read and
// change it as their files say; this file decides nothing. Private to the runtime.
#include "../step_arena.hpp"
#include "work_list.hpp"

#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/details/segment_plan.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/primitives.hpp>
#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cstreams::runtime {

struct StreamState {
  Buffer buffer;
  std::size_t count = 0;
  std::size_t capacity = 0;
  std::size_t limit = SIZE_MAX;
  bool known = true;
  std::uint32_t slot = no_slot;  // count slot of a variable stream
  std::string handed_to;         // the stream its buffer went to in the last run (PassSpec::hand_over)
  std::size_t peak_bytes = 0;    // the most its buffer held this run
  // In a sliced run: a gathered stream's items of earlier slices, which its producer
  // appends to and its growth keeps; another's items of earlier slices, for the stats.
  std::size_t base = 0;
  std::size_t earlier = 0;
  std::size_t run_items = 0;     // over the last run, every slice's
  bool partial = false;          // holds the last slice's items only (not gathered)
  std::size_t released = 0;      // the capacity memory pressure or a new run took before its producer ran
  // Emitted anew each run (not handed over, not gathered): within a run its buffer comes
  // from the step arena, and a new run gives it back.
  bool transient = false;
  std::size_t arena_at = StepArena::none;
  bool spent = false;  // within a run only (StreamGraph::within_run), and gone back this run
};

// An emitted stream of a pass: its registration segments' sizes (SegmentSizes, which
// SegmentPlanner plans) and buffers.
struct EmitterState : details::SegmentSizes {
  StreamId stream;
  StreamId handed_from;  // the input whose buffer the stream takes (PassSpec::hand_over), if any
  Buffer items;   // registration segments, from the step arena or the idle ones; held until the stage's counters are read
  std::size_t arena_at = StepArena::none;
  std::size_t needed = 0;         // bytes of segments the last execution asked for
  std::size_t segment_bytes = 0;  // of the segments this run's execution held
  Buffer counts;  // one count per segment
  std::size_t counts_at = StepArena::none;
  std::uint32_t overflow_slot = no_slot;
  // Segmented lock: this execution's segment offsets (the prefix sum of its counts,
  // then their total), and the last execution's, which plan this one's segments.
  Buffer offsets, plan;
};

// The plan the emitter's kernels and merge read: its own, else `no_plan` (one zero).
inline const Buffer& plan_of(const EmitterState& e, const Buffer& no_plan) { return e.planned ? e.plan : no_plan; }

struct PassState {
  const PassSpec* spec = nullptr;
  Kernel kernel;          // built for the scheduler's registration
  Kernel atomic_kernel;   // the fallback when segments would not fit: built on first need,
                          // or kernel itself where that is built for the global counter
  Kernel variant, atomic_variant;  // the same two of PassSpec::instead_while's kernel
  Registration mode = Registration::global_atomic;  // of the current execution
  bool atomic_this_run = false;
  bool handed_over = false;  // packed an output into its input's buffer this run
  bool ran = false;          // executed this run
  const Kernel& active(bool instead) const
  {
    const bool atomic = mode == Registration::global_atomic && atomic_kernel.get();
    if (instead) return atomic ? atomic_variant : variant;
    return atomic ? atomic_kernel : kernel;
  }
  std::vector<EmitterState> emitters;
  Buffer keep;
  std::size_t keep_at = StepArena::none;
  std::optional<ListState> list;
  std::vector<StreamId> inputs;
  PassStats stats;
};

}  // namespace cstreams::runtime
