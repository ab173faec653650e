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

/* Segmented-lock segments planned from the last run (cs_segment_base), then the spill
 * pool: group g < segments copies segment g, the groups after them the spilled items,
 * a work-item each. A segment holds about one emitting group's items, so a group starts
 * from its segment's bounds alone; one work-item per slot would first search for its
 * segment, a chain of dependent reads that held every group up. A spilled item's group
 * and rank follow the counts. Work-item 0 also completes `offsets` with the total at
 * [segments], so that they plan the next run's segments. */
__kernel void cs_merge_planned(__global const uint* items, const uint words, __global const uint* counts,
                               __global uint* offsets, const uint segments, __global const uint* plan,
                               const uint planned, const uint fresh, __global const uint* counters,
                               const uint spill_slot, __global uint* dst, const uint capacity)
{
  const uint g = (uint)get_group_id(0), lid = (uint)get_local_id(0), size = (uint)get_local_size(0);
  if (g == 0u && lid == 0u) offsets[segments] = offsets[segments - 1u] + counts[segments - 1u];
  if (g < segments) {
    const uint base = cs_segment_base(plan, planned, fresh, g);
    const uint held = min(counts[g], cs_segment_base(plan, planned, fresh, g + 1u) - base), o = offsets[g];
    for (uint j = lid; j < held; j += size)
      if (o + j < capacity) cs_copy_item(items, base + j, dst, o + j, words);
  } else {
    const uint k = (g - segments) * size + lid;
    if (k >= min(counters[spill_slot], segments * CS_SPILL_PER_GROUP)) return;
    const uint o = offsets[counts[segments + 2u * k]] + counts[segments + 2u * k + 1u];
    if (o < capacity) cs_copy_item(items, cs_segment_base(plan, planned, fresh, segments) + k, dst, o, words);
  }
}
