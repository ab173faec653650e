#pragma once
// From a stream graph to what the scheduler keeps of it: each stream's first buffer and
// its counter slot, which streams are transient (StreamState::transient), and the passes
// in execution order with their kernels and emitters. Runs once, as a Scheduler is made.
// Private to the runtime.
#include "states.hpp"
#include "stream_buffers.hpp"

#include <cstreams/runtime/scheduler.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cstreams::runtime {

class Context;

// The work-group size the pass's kernels launch with: its own where it asks for one no
// larger than the context's.
std::size_t work_group_of(const PassSpec& spec, const Context& context);

// Lays out `buffers`' streams and fills `passes` in execution order, their kernels built
// for `registration` (or the global counter, registration_of); returns the counter words
// the streams and emitters take.
std::uint32_t lay_out(Context& context, const StreamGraph& graph, Registration registration, StreamBuffers& buffers,
                      std::vector<PassState>& passes);

}  // namespace cstreams::runtime
