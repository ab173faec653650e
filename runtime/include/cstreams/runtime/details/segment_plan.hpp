#pragma once
// Registration segments planned from the last run (cl_kernels/runtime/registration.h):
// how many items an emitted stream's segments and spill pool hold for a launch, and
// what a launch's counts change in the plan. Owns this arithmetic alone: it holds no
// buffers and touches no device, so the scheduler allocates what it says and keeps the
// plan's offsets itself (runtime/src/scheduler/registrar.cpp). Private to the runtime.
#include <cstreams/runtime/registration.hpp>

#include <cstddef>
#include <cstdint>

namespace cstreams::runtime::details {

// Segmented lock: the spill pool's items per group that the last run did not plan.
constexpr std::uint64_t spill_per_group = 16;

// One emitter's plan: what the last execution's counts said, and this execution's sizes.
struct SegmentSizes {
  double expected = 0;     // items a work-item, before a run has planned the segments (PassSpec::expected_items)
  std::size_t group = 0;   // work-items a group of the pass's launches
  std::size_t segments = 0;          // of this execution: a group's (segmented lock) or a work-item's (lock-free)
  std::size_t segment_capacity = 0;  // lock-free: items a work-item's segment holds
  std::size_t planned = 0;        // segments the plan covers; 0: none yet
  std::size_t planned_total = 0;  // items they emitted
  // Segmented lock, where no plan fits: what a group may hold at most, from a forgotten
  // plan's total spread over this run's groups (0: no such total).
  std::size_t fresh = 0;
  // Segmented lock: the items the spill pool of this execution holds; what the last
  // execution planned from another run's counts spilled (adopt); and whether this
  // execution's plan is its own input's counts (a rerun).
  std::size_t pool = 0, spilled = 0;
  bool exact_plan = false;
};

// The rules for one registration mode on a device whose groups hold `work_group` work-items.
class SegmentPlanner {
public:
  SegmentPlanner(Registration mode, std::size_t work_group) : mode_(mode), work_group_(work_group) {}

  // Segments a launch of `global` work-items registers in.
  std::size_t segment_count(const SegmentSizes& s, std::size_t global) const;
  // What a segment the plan does not cover holds: a group's (or work-item's) expected items.
  std::size_t first_segment_capacity(const SegmentSizes& s) const;
  // Items the segments of `segments` groups hold, their spill pool included.
  std::uint64_t segment_items(const SegmentSizes& s, std::size_t segments) const;
  std::uint64_t spill_pool_items(const SegmentSizes& s, std::size_t segments) const;
  // Sizes this execution's segments and pool for a launch of `global` work-items.
  void prepare(SegmentSizes& s, std::size_t global) const;
  // Whether a launch's items overflowed its segments, given its overflow count.
  bool overflowed(Registration launched, const SegmentSizes& s, std::uint32_t overflow_count) const;

  // Drops a plan made for many more or fewer segments than `segments`.
  static void forget_stale_plan(SegmentSizes& s, std::size_t segments);
  // This execution's counts (`emitted` in all, `overflow_count` spilled) plan the next.
  static void adopt(SegmentSizes& s, std::size_t emitted, std::uint32_t overflow_count);

private:
  Registration mode_;
  std::size_t work_group_;
};

}  // namespace cstreams::runtime::details
