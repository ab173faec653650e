#include "run_reads.hpp"

#include <cstreams/runtime/context.hpp>

#include <cstring>

namespace cstreams::runtime {

void RunReads::add(StreamId stream, void* items, std::size_t bytes)
{
  const std::size_t at = reads_.empty() ? 0 : reads_.back().at + reads_.back().bytes;
  if (host_.bytes() < at + bytes) {
    // A run that threw may have left reads queued into the old memory.
    context_.finish();
    HostStaging more(context_, at + bytes, "reads after a run");
    if (at > 0) std::memcpy(more.data(), host_.data(), at);
    host_ = std::move(more);
  }
  reads_.push_back({stream, items, bytes, at});
}

void RunReads::requeue_all()
{
  for (Read& r : reads_) r.queued = false;
}

void RunReads::requeue(StreamId stream)
{
  for (Read& r : reads_)
    if (r.stream == stream) r.queued = false;
}

void RunReads::queue(const std::function<bool(StreamId)>& written, const BufferOf& buffer_of)
{
  for (Read& r : reads_) {
    if (r.queued || !written(r.stream)) continue;
    context_.read_queued(buffer_of(r.stream), landing(r), r.bytes);
    r.queued = true;
  }
}

void RunReads::finish(const BufferOf& buffer_of, Timeline* timeline)
{
  for (const Read& r : reads_) {
    if (!r.queued) context_.read(buffer_of(r.stream), landing(r), r.bytes, 0, timeline);
    std::memcpy(r.items, landing(r), r.bytes);
  }
  reads_.clear();
}

}  // namespace cstreams::runtime
