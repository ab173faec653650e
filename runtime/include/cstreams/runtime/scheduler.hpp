#pragma once
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/registration.hpp>
#include <cstreams/runtime/stream_graph.hpp>
#include <cstreams/runtime/timeline.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cstreams::runtime {

class Context;

struct SchedulerOptions {
  Registration registration = Registration::lock_free;
  bool profile = true;  // record OpenCL profiling events for per-pass device time
  // What lives within a run (registration segments, the streams passes emit anew each
  // run) shares one buffer, sized by the last run; false: each holds its own, the
  // segments through a pool of idle buffers shared between stages.
  bool step_arena = true;
};

struct PassStats {
  std::string name;
  std::uint64_t device_ns = 0;  // every launch issued for the pass, packing included
  unsigned launches = 0;
  unsigned reruns = 0;          // executions repeated after an overflow
  // A work list's rounds that had items (launches beyond them found the list empty),
  // items over all rounds, and the most in one round; in a run that went in slices,
  // added up over the slices (rounds and items) or the most of them (widest).
  unsigned rounds = 0;
  std::uint64_t list_items = 0;
  std::size_t widest_list = 0;
  // The pass's own: registration segments (those it held this run, shared with passes
  // of other stages), cull flags, work lists.
  std::size_t scratch_bytes = 0;
  std::size_t segment_bytes = 0;  // the registration segments alone
};

struct StreamStats {
  std::string name;
  bool variable = false;
  std::size_t count = 0;
  std::size_t capacity = 0;
  std::size_t bytes = 0;        // device memory held after the run
  std::size_t peak_bytes = 0;   // and the most it held during the run
  std::size_t items = 0;        // emitted over the run, every slice's (count: the last slice's)
};

struct RunStats {
  std::vector<PassStats> passes;    // in execution order
  std::vector<StreamStats> streams; // in declaration order
  std::uint64_t scheduler_ns = 0;   // counter clears and readbacks
  std::vector<Timeline::Entry> commands;  // every command the run recorded (profiling on), in queue order
  unsigned readbacks = 0;           // blocking counter transfers: one per stage and rerun
  std::size_t scratch_bytes = 0;    // segments (each buffer once), flags, offsets and scan levels
  std::size_t segment_bytes = 0;    // the registration segments alone, each buffer once
  unsigned slices = 1;              // of the sliced pass's input (1: not sliced, or in one slice)
  std::string sliced_pass;          // the pass whose input went in slices (of the global
                                    // counter, one where it fitted one), if any
  // From the first command's start to the last one's end.
  DeviceSpan span() const
  {
    DeviceSpan s;
    for (const auto& c : commands) s.add(c.start, c.end);
    return s;
  }
};

// Runs a StreamGraph on one device. It builds every kernel at construction, owns the
// streams' buffers and all scratch memory, inserts registration and compaction, and
// grows and reruns on overflow so that no item is ever dropped.
//
// Execution goes in stages: a pass that reads a variable-length stream produced in the
// current stage needs its count, so the stage ends there and the host reads every
// counter of the stage in one transfer. Streams that overflowed grow; the passes that
// produced them run again (only the packing, when the segments held everything).
//
// A pass that does not fit the device's memory even in a stage of its own, through the
// global counter, runs in slices: over one slice of its input stream at a time (an
// OpenCL sub-buffer), followed each time by the passes that depend on what it emits,
// all through the global counter. Passes after it that do not depend on it run once,
// in the first slice, and the launch streams those passes emit into the sliced ones
// count only there. Streams marked StreamGraph::gather collect every slice's items;
// other outputs of the sliced passes hold the last slice's. Slices double until one
// fits; a scheduler keeps their number and the input they cut for the runs after, so
// that a step under a memory budget does not fail first each time: a larger input
// starts from that number, a smaller one takes as much fewer slices, down to one
// (still through the global counter). A slice's work-items count from 0, so a pass
// that may be sliced emits what it reads, not its position in its input.
class Scheduler {
public:
  Scheduler(Context& context, StreamGraph graph, SchedulerOptions options = {});
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  void run();
  // Gives back the scratch that holds nothing between runs (registration segments with
  // their counts, cull flags, work lists; the next run allocates what it needs again,
  // planned as before) and returns whether any memory went back: room for device work
  // outside the graph that runs short of memory.
  bool release_idle_scratch();
  // Slices of the step arena's free space between runs, one of each size (at the
  // device's base-address alignment); none without the arena or where its free space
  // does not hold them all. For device work between runs that would otherwise hold
  // memory of its own through the runs. The next run writes over them: drop them before
  // it.
  std::vector<Buffer> borrow_idle_scratch(const std::vector<std::size_t>& sizes) const;

  // Host transfers. Uploading to a fixed stream resizes it to `count` items;
  // uploading to a variable stream sets its count (growing it if needed).
  void upload(StreamId stream, const void* items, std::size_t count);
  void download(StreamId stream, void* items, std::size_t count) const;
  // Reads the first `count` items of a fixed stream into `items` as the next run that
  // completes ends (a run that throws, a stop say, leaves the read to the next one):
  // queued ahead of the run's last counter read where every pass that writes the
  // stream has run by then, so that they come back without a round trip of their own,
  // else read once the run is done. `items` must stay valid until then; only a run
  // that completes writes them.
  void read_after_run(StreamId stream, void* items, std::size_t count);
  template <class T> void upload(StreamId s, const std::vector<T>& items) { upload(s, items.data(), items.size()); }
  template <class T> std::vector<T> download(StreamId s) const
  {
    std::vector<T> items(count(s));
    download(s, items.data(), items.size());
    return items;
  }

  // Fixed streams only: items [first, first + count) without resizing, and a copy of
  // items between two streams of one element size (queued on the device).
  void write(StreamId stream, std::size_t first, const void* items, std::size_t count);
  // As write(), queued: returns at once and reads `items` until the event completes.
  Handle<cl_event> write_queued(StreamId stream, std::size_t first, const void* items, std::size_t count);
  void copy(StreamId source, std::size_t source_first, StreamId destination, std::size_t destination_first,
            std::size_t count);

  std::size_t count(StreamId stream) const;
  std::size_t capacity(StreamId stream) const;
  // Sets a variable stream's capacity, smaller ones included; the items that still fit
  // are kept.
  void set_capacity(StreamId stream, std::size_t items);
  // Caps how far a variable stream may grow: a run that needs more stops with
  // StreamLimitExceeded instead of growing it (a caller that can make do with less,
  // such as a front kept at coarser levels, changes its parameters and runs again).
  void set_limit(StreamId stream, std::size_t items);
  // Sets a fixed stream's item count; contents are undefined until written.
  void resize(StreamId stream, std::size_t items);
  // Exchanges two streams' buffers and counts (ping-pong between runs).
  void swap(StreamId a, StreamId b);
  const Buffer& buffer(StreamId stream) const;

  // Called on the run's thread before each blocking read of a stage's counters, while
  // the device works through the stage: host work of the caller's that would otherwise
  // wait for the run to end and then stand between it and the next (queueing uploads
  // for the next run). It must not touch this scheduler's streams' sizes.
  void on_counter_read(std::function<void()> work);

  void set(ParamId param, const void* bytes, std::size_t size);
  template <class T> void set(ParamId p, const T& value) { set(p, &value, sizeof(T)); }

  const StreamGraph& graph() const;
  // Pass names in execution order.
  std::vector<std::string> execution_order() const;
  // The last run's figures, as its streams stood when it ended. They are gathered on
  // the first call for them or before the first change to the streams after the run,
  // so that the host's next launch need not wait for them.
  const RunStats& stats() const;
  Registration registration() const;

private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cstreams::runtime
