#pragma once
// A launch's kernel arguments: the pass's own (PassSpec::args), then those the scheduler
// appends for its work list's state, each emitted stream's registration and a culling
// pass's flags, in the order the kernels declare them (CS_EMITTER_PARAMS in
// cl_kernels/runtime/registration.h). Owns that order; reads the scheduler's state and
// changes none of it. Private to the runtime.
#include "states.hpp"

#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/details/segment_plan.hpp>
#include <cstreams/runtime/kernel.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <vector>

namespace cstreams::runtime {

// Where arguments come from.
struct Bindings {
  const StreamGraph& graph;
  const std::vector<StreamState>& streams;
  const std::vector<std::vector<unsigned char>>& params;  // as Scheduler::set left them
  const Buffer& counters;                                 // the run's counters
  const Buffer& no_plan;                                  // the plan of segments that have none
  const details::SegmentPlanner& planner;
};

// Binds the pass's own arguments; returns the index of the next one. Throws naming the
// pass and the parameter where a parameter was never set.
unsigned bind_own_args(const Bindings& b, const PassSpec& spec, const Kernel& k);
// Binds every argument of the pass's launch of `k`, in its current registration mode.
void bind_args(const Bindings& b, const PassState& p, const Kernel& k);

}  // namespace cstreams::runtime
