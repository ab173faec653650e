#pragma once
#include <cstreams/runtime/handle.hpp>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace cstreams::runtime {

// From the earliest start to the latest end of commands on one device: their time and
// the device's idle time between them (launch latency, the host's round trips).
struct DeviceSpan {
  std::uint64_t start = UINT64_MAX, end = 0;  // none yet: an empty span
  void add(std::uint64_t from, std::uint64_t to)
  {
    start = from < start ? from : start;
    end = to > end ? to : end;
  }
  std::uint64_t nanoseconds() const { return end > start ? end - start : 0; }
};

// Collects the profiling events of a run's launches and transfers, labelled by what
// issued them, and turns them into device nanoseconds once the queue has finished.
class Timeline {
public:
  struct Entry {
    std::string label;
    std::uint64_t nanoseconds = 0;
    // On the device's clock: when the host queued the command, and when it ran. A
    // command queued after its device had gone idle shows the host's turnaround (from
    // the previous command's end to its queueing) apart from the launch latency (from
    // its queueing to its start).
    std::uint64_t queued = 0, start = 0, end = 0;
    // On the host's clock, when the command was queued: set beside `queued`, it tells
    // where the host was while the device ran or waited, before a step's first command
    // and after its last included.
    std::chrono::steady_clock::time_point host_queued;
  };

  void record(std::string label, Handle<cl_event> event);
  // Waits for the recorded events (of one in-order queue) and returns their durations
  // in record order.
  std::vector<Entry> resolve() const;
  void clear() { pending_.clear(); }
  bool empty() const { return pending_.empty(); }

private:
  struct Pending {
    std::string label;
    Handle<cl_event> event;
    std::chrono::steady_clock::time_point host_queued;
  };
  std::vector<Pending> pending_;
};

}  // namespace cstreams::runtime
