#pragma once
// Fixed streams a run reads back as it ends (Scheduler::read_after_run): where the reads
// land, which are queued ahead of a counter read once every writer of their stream has
// run (so that they come back with it, at no round trip of their own), and the copy to
// the caller's memory once the run is done. Owns those reads and their host memory; it
// launches nothing and allocates no device memory: Flush says which streams are written
// and lends their buffers (scheduler/flush.cpp). Private to the runtime.
#include <cstreams/runtime/buffer.hpp>
#include <cstreams/runtime/host_staging.hpp>
#include <cstreams/runtime/stream_graph.hpp>

#include <cstddef>
#include <functional>
#include <vector>

namespace cstreams::runtime {

class Context;
class Timeline;

class RunReads {
public:
  using BufferOf = std::function<const Buffer&(StreamId)>;

  explicit RunReads(Context& context) : context_(context) {}

  // The next run to complete copies `bytes` of the stream's buffer to `items`.
  void add(StreamId stream, void* items, std::size_t bytes);
  bool empty() const { return reads_.empty(); }
  // A run starts, or a writer of `stream` runs again: its read waits for it.
  void requeue_all();
  void requeue(StreamId stream);
  // Before a counter read: queues the reads of the streams `written` says are.
  void queue(const std::function<bool(StreamId)>& written, const BufferOf& buffer_of);
  // As a run ends: what no counter read brought back is read now, every read is copied
  // to its caller, and the reads are done.
  void finish(const BufferOf& buffer_of, Timeline* timeline);

private:
  struct Read {
    StreamId stream;
    void* items;
    std::size_t bytes;
    std::size_t at;  // in host_
    bool queued = false;
  };
  void* landing(const Read& r) const { return static_cast<unsigned char*>(host_.data()) + r.at; }

  Context& context_;
  std::vector<Read> reads_;
  // Where the reads land, pinned: a queued read into pageable memory made an H200's
  // step 0.08 ms longer (cloth-ball, earliest times alone).
  HostStaging host_;
};

}  // namespace cstreams::runtime
