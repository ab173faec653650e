#pragma once
// A run's figures (RunStats): device time per pass from the timeline's commands, what
// the scheduler launched and ran again, and the memory each pass, stream and the shared
// scratch held. Owns how they are added up; reads the scheduler's state after a run and
// changes nothing of it but the figures it keeps for the passes and streams (PassState::
// stats, StreamState::run_items). Private to the runtime.
#include "states.hpp"

#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <cstddef>
#include <vector>

namespace cstreams::runtime {

class StepArena;

// What a run's figures are read from.
struct RunFigures {
  const StreamGraph& graph;
  const Timeline& timeline;
  std::size_t shared_scratch_bytes;  // the scan's scratch and the lock-free offsets
  const std::vector<Buffer>& idle_segments;
  const StepArena& arena;
  std::vector<StreamState>& streams;
  std::vector<PassState>& passes;
};

// Completes `stats`, which holds the run's counts of launches and reads already.
void collect_stats(RunStats& stats, const RunFigures& figures);

}  // namespace cstreams::runtime
