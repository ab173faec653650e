/* Packing kernels the scheduler inserts: the scatter of a compaction and the merge
 * of registration segments. Items are copied as `words` 32-bit words, so one kernel
 * serves every element type. Writes past `capacity` are dropped; the count in the
 * counter slot still says how many there were, and the host grows and reruns. */
#include "common.h"
#include "registration.h"

inline void cs_copy_item(__global const uint* src, size_t from, __global uint* dst, size_t to, uint words)
{
  for (uint w = 0; w < words; ++w) dst[to * words + w] = src[from * words + w];
}

__kernel void cs_scatter(__global const uint* src, const uint words, __global const uint* keep,
                         __global const uint* offsets, const uint n, __global uint* dst, const uint capacity)
{
  const size_t i = get_global_id(0);
  if (i >= n || !keep[i]) return;
  const uint o = offsets[i];
  if (o < capacity) cs_copy_item(src, i, dst, o, words);
}

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

/* The segment holding slot i, where base(lo) <= i < base(hi). */
inline uint cs_find_segment(__global const uint* plan, const uint planned, const uint fresh, const uint i, uint lo,
                            uint hi)
{
  while (hi - lo > 1u) {
    const uint mid = lo + (hi - lo) / 2u;
    if (cs_segment_base(plan, planned, fresh, mid) <= i) lo = mid;
    else hi = mid;
  }
  return lo;
}

/* Segmented-lock segments planned from the last run (cs_segment_base), then the spill
 * pool: one work-item per slot. A group's slots span few segments, so the group's first
 * and last work-items bisect all segments and the others only between what they found.
 * A spilled item's group and rank follow the counts. Work-item 0 also completes
 * `offsets` with the total at [segments], so that they plan the next run's segments. */
__kernel void cs_merge_planned(__global const uint* items, const uint words, __global const uint* counts,
                               __global uint* offsets, const uint segments, __global const uint* plan,
                               const uint planned, const uint fresh, __global const uint* counters,
                               const uint spill_slot, __global uint* dst, const uint capacity)
{
  __local uint range[2];
  const uint i = (uint)get_global_id(0), lid = (uint)get_local_id(0), last = (uint)get_local_size(0) - 1u;
  const uint pool = cs_segment_base(plan, planned, fresh, segments);
  const uint first = i - lid;
  if (lid == 0u) range[0] = first < pool ? cs_find_segment(plan, planned, fresh, first, 0u, segments) : 0u;
  if (lid == last)
    range[1] = first < pool ? cs_find_segment(plan, planned, fresh, min(first + last, pool - 1u), 0u, segments) + 1u : 1u;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (i == 0u) offsets[segments] = offsets[segments - 1u] + counts[segments - 1u];
  uint o;
  if (i < pool) {
    const uint s = cs_find_segment(plan, planned, fresh, i, range[0], range[1]);
    const uint j = i - cs_segment_base(plan, planned, fresh, s);
    if (j >= counts[s]) return;
    o = offsets[s] + j;
  } else {
    const uint k = i - pool;
    if (k >= min(counters[spill_slot], segments * CS_SPILL_PER_GROUP)) return;
    o = offsets[counts[segments + 2u * k]] + counts[segments + 2u * k + 1u];
  }
  if (o < capacity) cs_copy_item(items, i, dst, o, words);
}
