#pragma once
#include <cstreams/runtime/context.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/scheduler.hpp>

#include <cstddef>
#include <vector>

namespace cstreams {

// Positions that callers give object by object between steps, gathered in pinned host
// memory and queued as the next step starts: one write per run of adjacent objects in
// a stream, returning at once, where a blocking write per object and stream cost a
// 300-object scene 600 writes and 4.5 of its 5.6 ms a step on the H100.
class PositionWrites {
public:
  explicit PositionWrites(runtime::Context& context) : context_(context) {}

  // Room for items [first, first + count) of `stream`, `item_bytes` each, that the caller
  // fills at once; later calls may move it.
  void* stage(runtime::StreamId stream, std::size_t first, std::size_t count, std::size_t item_bytes);
  // Queues what was staged since the last call ahead of the work queued after it; a
  // stream's later items win where two overlap.
  void queue(runtime::Scheduler& scheduler);

private:
  struct Run {
    std::size_t first, count, offset;  // items in the stream; bytes in the staging
  };
  struct Staged {
    runtime::StreamId stream;
    std::size_t item_bytes = 0, used = 0;
    runtime::HostStaging memory;
    std::vector<Run> runs;
  };

  runtime::Context& context_;
  std::vector<Staged> staged_;
  // The writes last queued, which read the staging until they complete.
  std::vector<runtime::Handle<cl_event>> queued_;
};

}  // namespace cstreams
