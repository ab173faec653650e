/* Packing kernels the scheduler inserts: the merge of registration segments (a
 * compaction's scatter is part of its scan, scan.cl). Writes past `capacity` are
 * dropped; the count in the counter slot still says how many there were, and the host
 * grows and reruns. */
#include "common.h"
#include "copy.h"
#include "group_sum.h"
#include "registration.h"

/* Lock-free per-thread segments: segment s holds counts[s] items, its item j at
 * j * segments + s, so that threads writing their j-th item together touch
 * neighbouring words. */
__kernel void cs_merge_interleaved(__global const uint* items, const uint words, __global const uint* counts,
                                   __global const uint* offsets, const uint segments, const uint segment_capacity,
                                   __global uint* dst, const uint capacity)
{
  const size_t i = get_global_id(0);
  const uint s = (uint)(i % segments), j = (uint)(i / segments);
  if (s >= segments || j >= min(counts[s], segment_capacity)) return;
  const uint o = offsets[s] + j;
  if (o < capacity) cs_copy_item(items, i, dst, o, words);
}

/* Segmented-lock segments planned from the last run (cs_segment_base), then the spill
 * pool. Each of the first groups copies `per_group` neighbouring segments (at most
 * CS_MERGE_SEGMENTS and the group's size), the groups after them the spilled items, a
 * work-item each. A group first reads its segments' bounds, then copies them as one run
 * of items, each work-item walking forward through the group's segments two items at
 * once (cs_copy_two_items). Segments hold about one emitting group's items, often fewer
 * than a group has work-items: one group a segment left most work-items idle while
 * tens of thousands of groups waited to be dispatched (the H200 took 37 us for a front
 * update's 19 MB of triangle pairs). A spilled item's group and rank follow the counts.
 * Work-item 0 (with own_offsets, the last segment's group) also completes `offsets`
 * with the total at [segments], so that they plan the next run's segments. */
#define CS_MERGE_SEGMENTS 64u

/* With `own_offsets` (no item spilled, and few segments: the host decides) nothing has
 * scanned the counts: each group adds up the counts before its segments and writes
 * their offsets itself, a launch fewer. */
__kernel void cs_merge_planned(__global const uint* items, const uint words, __global const uint* counts,
                               __global uint* offsets, const uint segments, __global const uint* plan,
                               const uint planned, const uint fresh, __global const uint* counters,
                               const uint spill_slot, const uint pool, __global uint* dst, const uint capacity,
                               const uint per_group, const uint own_offsets)
{
  __local uint start[CS_MERGE_SEGMENTS + 1u], from[CS_MERGE_SEGMENTS], to[CS_MERGE_SEGMENTS];
  __local uint partial[CS_WG_SIZE];
  const uint g = (uint)get_group_id(0), lid = (uint)get_local_id(0), size = (uint)get_local_size(0);
  if (!own_offsets && g == 0u && lid == 0u) offsets[segments] = offsets[segments - 1u] + counts[segments - 1u];
  const uint groups = (segments + per_group - 1u) / per_group;
  /* Every group reaches the barriers, the spill pool's too: under a branch that whole
   * groups took, pocl 3.1 lost items now and then (test_scheduler). */
  const uint first = g * per_group, k = g < groups ? min(per_group, segments - first) : 0u;
  const uint before = own_offsets ? cs_group_sum_before(counts, min(first, segments), partial) : 0u;
  if (lid < k) {
    const uint s = first + lid, base = cs_segment_base(plan, planned, fresh, s);
    start[lid + 1u] = min(counts[s], cs_segment_base(plan, planned, fresh, s + 1u) - base);
    from[lid] = base;
    if (!own_offsets) to[lid] = offsets[s];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  uint end = 0;
  if (lid < k)
    for (uint i = 0; i <= lid; ++i) end += start[i + 1u];
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid < k) start[lid + 1u] = end;
  if (lid == 0u) start[0] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (own_offsets && lid < k) {
    const uint s = first + lid, at = before + start[lid];
    to[lid] = at;
    offsets[s] = at;
    if (s == segments - 1u) offsets[segments] = at + counts[s];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (g < groups) {
    uint s = 0;
    const uint total = start[k];
    for (uint j = lid; j < total; j += 2u * size) {
      uint from_at[2], to_at[2];
      for (uint u = 0; u < 2u; ++u) {
        const uint i = j + u * size;
        from_at[u] = 0;
        to_at[u] = capacity; /* past the group's items: nothing to copy */
        if (i < total) {
          while (start[s + 1u] <= i) ++s;
          from_at[u] = from[s] + (i - start[s]);
          to_at[u] = to[s] + (i - start[s]);
        }
      }
      cs_copy_two_items(items, from_at, dst, to_at, capacity, words);
    }
  } else {
    const uint x = (g - groups) * size + lid;
    if (x < min(counters[spill_slot], pool)) {
      const uint o = offsets[counts[segments + 2u * x]] + counts[segments + 2u * x + 1u];
      if (o < capacity) cs_copy_item(items, cs_segment_base(plan, planned, fresh, segments) + x, dst, o, words);
    }
  }
}
