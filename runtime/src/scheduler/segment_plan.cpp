#include <cstreams/runtime/details/segment_plan.hpp>

#include <algorithm>
#include <cmath>

namespace cstreams::runtime::details {

std::size_t SegmentPlanner::segment_count(const SegmentSizes& s, std::size_t global) const
{
  return mode_ == Registration::segmented_lock ? global / s.group : global;
}

std::size_t SegmentPlanner::first_segment_capacity(const SegmentSizes& s) const
{
  const bool per_group = mode_ == Registration::segmented_lock;
  const std::size_t expected =
      std::max<std::size_t>(1, std::size_t(std::ceil(s.expected * double(per_group ? s.group : 1))));
  return per_group && s.fresh > 0 ? std::min(expected, s.fresh) : expected;
}

// The lock-free segments each hold as much as the busiest of the last run;
// segmented-lock ones follow the last run's plan (cs_segment_base at `segments`,
// bounded by the plan's total), then the spill pool.
std::uint64_t SegmentPlanner::segment_items(const SegmentSizes& s, std::size_t segments) const
{
  if (segments == 0) return 0;
  if (mode_ == Registration::lock_free) return std::uint64_t(segments) * s.segment_capacity;
  const std::uint64_t planned = std::min(segments, s.planned), total = s.planned_total;
  return total + total / 8 + (segments - planned) * first_segment_capacity(s) + spill_pool_items(s, segments);
}

// A planned group spills only what it emits beyond its last run's and an eighth: the
// pool holds twice what the last run spilled (adopt), and an item a group or one
// group's burst of 16 items a work-item, whichever is more (16 a group took 9 MiB of
// n-body's step at its peak, and none spilled). A rerun, planned from its own input,
// spills nothing. A group the plan lacks gets 16 items where it has the context's
// size, and as many fewer as it has fewer work-items: the decomposition's first run
// in groups of 128 held 9 MiB more on n-body at 16 a group, with each spilled item's
// two words of place.
std::uint64_t SegmentPlanner::spill_pool_items(const SegmentSizes& s, std::size_t segments) const
{
  const std::uint64_t planned = std::min(segments, s.planned), spilled = s.exact_plan ? 0 : s.spilled;
  const std::uint64_t least = planned > 0 ? std::max<std::uint64_t>(planned, spill_per_group * s.group) : 0;
  const std::uint64_t unplanned = std::max<std::uint64_t>(1, spill_per_group * s.group / work_group_);
  return std::max(least, 2 * spilled) + (segments - planned) * unplanned;
}

void SegmentPlanner::prepare(SegmentSizes& s, std::size_t global) const
{
  s.segments = segment_count(s, global);
  s.pool = mode_ == Registration::segmented_lock ? std::size_t(spill_pool_items(s, s.segments)) : 0;
}

bool SegmentPlanner::overflowed(Registration launched, const SegmentSizes& s, std::uint32_t overflow_count) const
{
  if (launched == Registration::segmented_lock) return overflow_count > s.pool;
  return launched == Registration::lock_free && overflow_count > s.segment_capacity;
}

// A plan from a run with many more or fewer groups (the burst of a first step searched
// from the roots, say) says nothing about this one's groups: they start afresh. Its
// total still says how much the pass emits where its input is the last run's output
// (the second step's front update, over the front the first step's search found), so
// no group starts with more than that total spread evenly, and an eighth more: cloth-
// ball's second step held 112 MB of segments sized by the expected items, 80 MB in
// later steps. Where the pass runs in slices, the expected items are fewer.
void SegmentPlanner::forget_stale_plan(SegmentSizes& s, std::size_t segments)
{
  if (!(segments + s.planned / 8 < s.planned || segments > s.planned + s.planned / 8)) return;
  const std::size_t total = s.planned_total + s.planned_total / 8;
  if (total > 0 && segments > 0) s.fresh = (total + segments - 1) / segments;
  s.planned = s.planned_total = 0;
}

// Where this execution's segments were planned from the run before, what it spilled
// sizes the next pool: how much a step outgrows the one before, or how far its groups'
// work moved. The count goes on past the pool, so a pool that overflowed takes at once
// what the next step needs if it outgrows this one as much: a sequence whose front grew
// a fifth a step (the 1.5M-triangle sheet) had run its front update twice in most steps
// while the pool grew fourfold a step. Up to half of what it emitted, so that after a
// burst (a step where contact surges) the next step's pool holds no more than that step
// emitted. So too where the plan was forgotten and the groups each held the last total
// spread evenly (forget_stale_plan): what spilled then is how unevenly the groups
// emit, which a front that grows by more than an eighth a step keeps doing, and each of
// the 1.5M-triangle sheet's growing steps had run its front update twice with a pool
// sized before its growth began. Not an unplanned execution's (a first step's,
// searched from the roots: cloth-ball's next steps then peaked 11% above a settled
// one), nor a rerun's, planned from its own counts.
void SegmentPlanner::adopt(SegmentSizes& s, std::size_t emitted, std::uint32_t overflow_count)
{
  if ((s.planned > 0 || s.fresh > 0) && !s.exact_plan)
    s.spilled = std::min<std::size_t>(overflow_count, emitted / 2);
  s.planned = s.segments;
  s.planned_total = emitted;
  s.fresh = 0;
  s.exact_plan = false;
}

}  // namespace cstreams::runtime::details
