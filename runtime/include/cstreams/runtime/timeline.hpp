#pragma once
#include <cstreams/runtime/handle.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace cstreams::runtime {

// Collects the profiling events of a run's launches and transfers, labelled by what
// issued them, and turns them into device nanoseconds once the queue has finished.
class Timeline {
public:
  struct Entry {
    std::string label;
    std::uint64_t nanoseconds = 0;
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
  };
  std::vector<Pending> pending_;
};

}  // namespace cstreams::runtime
