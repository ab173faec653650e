#pragma once
// The run's counters: a word for each variable stream (its items) and each emitter (its
// spilled items), then each work list's counts; on the device, and as the last read
// brought them. Owns their layout, when they are cleared and how they are read; not what
// a word means (the parts that own streams, segments and lists read their own words).
// Private to the runtime.
#include "states.hpp"

#include <cstreams/runtime/buffer.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cstreams::runtime {

class Context;
class Timeline;

class Counters {
public:
  // `slots` words for the streams and emitters, then the passes' lists' counts, each
  // where a sub-buffer may start (ListState::counts views them).
  Counters(Context& context, std::vector<PassState>& passes, std::size_t slots, Timeline* timeline);

  const Buffer& device() const { return counters_; }
  std::uint32_t operator[](std::size_t slot) const { return host_[slot]; }
  // A work list's counts as the last counter read (or list read) brought them.
  std::uint32_t* list_counts(const ListState& l) { return host_.data() + l.counts_at; }

  // As a run starts: the counters cleared during the last run, else every one cleared.
  void start_run();
  // Every counter zero, the work lists' counts among them.
  void clear_all();
  void set(std::uint32_t slot, std::uint32_t value);
  // The next run's counters cleared while the device is busy with this one: a run that
  // starts with them clear starts with its first kernel (a clear first held an H200's
  // first launch back by 10-20 us).
  void clear_next();
  // Every counter in one blocking transfer.
  void read();

private:
  void lists_cleared();

  Context& context_;
  std::vector<PassState>& passes_;
  Timeline* timeline_;
  std::vector<std::uint32_t> host_;
  Buffer counters_, next_;
  bool next_clear_ = false;
};

}  // namespace cstreams::runtime
