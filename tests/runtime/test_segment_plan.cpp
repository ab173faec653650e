// The sizing rules of registration segments (runtime/details/segment_plan.hpp), on the
// host alone: what a launch's segments and spill pool hold before and after a plan, and
// what a launch's counts leave for the next. test_registrar.cpp runs them on a
// device.
#include <cstreams/runtime/details/segment_plan.hpp>

#include <catch2/catch.hpp>

using namespace cstreams::runtime;
using namespace cstreams::runtime::details;

namespace {

SegmentSizes emitter(double expected, std::size_t group)
{
  SegmentSizes s;
  s.expected = expected;
  s.group = group;
  return s;
}

// A plan from a run of `groups` segmented-lock groups that emitted `total` items.
SegmentSizes planned(std::size_t groups, std::size_t total)
{
  SegmentSizes s = emitter(1.5, 256);
  s.planned = groups;
  s.planned_total = total;
  return s;
}

}  // namespace

TEST_CASE("segments no run has planned hold the expected items of a group, or of a work-item", "[runtime][quick]")
{
  const SegmentPlanner locked(Registration::segmented_lock, 256), free(Registration::lock_free, 256);
  SegmentSizes s = emitter(1.5, 256);
  CHECK(locked.first_segment_capacity(s) == 384);
  CHECK(free.first_segment_capacity(s) == 2);
  CHECK(locked.segment_count(s, 256 * 40) == 40);
  CHECK(free.segment_count(s, 256 * 40) == 256 * 40);
  // A forgotten plan's total, spread over this run's groups, caps them.
  s.fresh = 100;
  CHECK(locked.first_segment_capacity(s) == 100);
  // Unplanned groups of the context's size each add 16 items of spill pool.
  CHECK(locked.spill_pool_items(s, 40) == 40 * 16);
  CHECK(locked.segment_items(s, 40) == 40 * 100 + 40 * 16);
}

TEST_CASE("planned segments hold their last run's items and an eighth, and a pool for what spills", "[runtime][quick]")
{
  const SegmentPlanner planner(Registration::segmented_lock, 256);
  SegmentSizes s = planned(10, 8000);
  // At least an item a group, or 16 a work-item of one group; and two groups the plan
  // lacks, with 384 items and 16 of pool each.
  CHECK(planner.spill_pool_items(s, 12) == 4096 + 2 * 16);
  CHECK(planner.segment_items(s, 12) == 8000 + 1000 + 2 * 384 + 4096 + 2 * 16);
  // A pool twice what the last run spilled, where that is more.
  s.spilled = 5000;
  CHECK(planner.spill_pool_items(s, 10) == 10000);
  // A rerun, planned from its own counts, spills nothing.
  s.exact_plan = true;
  CHECK(planner.spill_pool_items(s, 10) == 4096);
  planner.prepare(s, 256 * 10);
  CHECK(s.segments == 10);
  CHECK(s.pool == 4096);
  // A pass in groups of 64 on a device of 256: an unplanned group's pool is a quarter.
  SegmentSizes small = emitter(1.5, 64);
  CHECK(planner.spill_pool_items(small, 8) == 8 * 4);
}

TEST_CASE("a launch's counts plan the next, and a plan for another number of groups is forgotten", "[runtime][quick]")
{
  SegmentSizes s = planned(100, 800);
  s.segments = 105;
  SegmentPlanner::forget_stale_plan(s, 105);  // within an eighth: kept
  CHECK(s.planned == 100);
  SegmentPlanner::forget_stale_plan(s, 200);
  CHECK(s.planned == 0);
  CHECK(s.planned_total == 0);
  CHECK(s.fresh == (900 + 199) / 200);

  // What a launch planned from the run before spilled sizes the next pool, up to half
  // of what it emitted.
  s = planned(100, 800);
  s.segments = 120;
  SegmentPlanner::adopt(s, 1000, 300);
  CHECK(s.spilled == 300);
  CHECK(s.planned == 120);
  CHECK(s.planned_total == 1000);
  CHECK(s.fresh == 0);
  s.segments = 120;
  SegmentPlanner::adopt(s, 1000, 900);
  CHECK(s.spilled == 500);
  // Nor does a plan forgotten for another number of groups: what spilled from groups
  // that each held the last total spread evenly sizes the next pool.
  s = planned(100, 800);
  SegmentPlanner::forget_stale_plan(s, 200);
  s.segments = 200;
  SegmentPlanner::adopt(s, 1200, 400);
  CHECK(s.spilled == 400);
  CHECK(s.planned == 200);
  CHECK(s.fresh == 0);
  // Neither an unplanned launch's spill nor a rerun's says how a step outgrows the last.
  SegmentSizes first = emitter(1.5, 256);
  first.segments = 40;
  SegmentPlanner::adopt(first, 50000, 40000);
  CHECK(first.spilled == 0);
  CHECK(first.planned == 40);
  SegmentSizes rerun = planned(40, 50000);
  rerun.exact_plan = true;
  rerun.segments = 40;
  SegmentPlanner::adopt(rerun, 50000, 7);
  CHECK(rerun.spilled == 0);
  CHECK_FALSE(rerun.exact_plan);
}

TEST_CASE("a launch overflowed where its spill outgrew the pool, or a work-item its segment", "[runtime][quick]")
{
  const SegmentPlanner planner(Registration::segmented_lock, 256);
  SegmentSizes s;
  s.pool = 100;
  s.segment_capacity = 8;
  CHECK_FALSE(planner.overflowed(Registration::segmented_lock, s, 100));
  CHECK(planner.overflowed(Registration::segmented_lock, s, 101));
  CHECK_FALSE(planner.overflowed(Registration::lock_free, s, 8));
  CHECK(planner.overflowed(Registration::lock_free, s, 9));
  CHECK_FALSE(planner.overflowed(Registration::global_atomic, s, 1000000));
}
