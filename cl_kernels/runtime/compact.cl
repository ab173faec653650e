/* Packing kernels the scheduler inserts: the scatter of a compaction and the merge
 * of registration segments. Items are copied as `words` 32-bit words, so one kernel
 * serves every element type. Writes past `capacity` are dropped; the count in the
 * counter slot still says how many there were, and the host grows and reruns. */
#include "common.h"

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

/* Segment s holds counts[s] items. With `interleaved` (lock-free per-thread segments)
 * item j of segment s sits at j * segments + s, so that threads writing their j-th
 * item together touch neighbouring words; otherwise at s * segment_capacity + j. */
__kernel void cs_merge_segments(__global const uint* items, const uint words, __global const uint* counts,
                                __global const uint* offsets, const uint segments, const uint segment_capacity,
                                const uint interleaved, __global uint* dst, const uint capacity)
{
  const size_t i = get_global_id(0);
  uint s, j;
  if (interleaved) {
    s = (uint)(i % segments);
    j = (uint)(i / segments);
  } else {
    s = (uint)(i / segment_capacity);
    j = (uint)(i % segment_capacity);
  }
  if (s >= segments || j >= min(counts[s], segment_capacity)) return;
  const uint o = offsets[s] + j;
  if (o < capacity) cs_copy_item(items, i, dst, o, words);
}
