#ifndef CSTREAMS_RUNTIME_WORKLIST_H
#define CSTREAMS_RUNTIME_WORKLIST_H
/* The rounds of a work list (Worklist in runtime/stream_graph.hpp), as a round kernel
 * uses them:
 *
 *   __local uint group[2];
 *   const uint n = cs_worklist_items(counts, round, capacity);
 *   for (uint base = get_group_id(0) * get_local_size(0); base < n; base += get_global_size(0)) {
 *     const uint i = base + get_local_id(0);
 *     ... k: the items this work-item appends (none where i >= n)
 *     const uint at = cs_worklist_append(group, counts, round, k);  // every work-item of the group
 *     for (uint j = 0; j < k; ++j) if (cs_worklist_fits(counts, capacity, at + j)) out[at + j] = ...;
 *   }
 *
 * The counts start as zeros, and the seed sets them up itself: every seed calls
 * cs_worklist_seed_begin, which counts its n first items in counts[0] and sets
 * counts[9], so the host writes nothing before a seed. counts[r % 3] holds the items of
 * round r: a seed's extra first items add to counts[0] too, and go after the n first
 * ones, where counts[12] places them. Round r appends to counts[(r + 1) % 3] and clears
 * counts[(r + 2) % 3], which round r - 1 read and round r + 1 appends to, so no launch
 * is needed between rounds. An append past the capacity writes nothing and raises counts[3] to the
 * capacity it needed. The round after one that overflowed finds more items than the
 * lists hold: it and every round after it do nothing (counts[10] marks it), so the
 * overflowing round's input stays whole. The host grows the lists, keeping that input,
 * and runs the round again with counts[11] set to its number plus one: a replay, in
 * which the round appends what it appended before and applies nothing twice (a round
 * kernel asks cs_worklist_replay, and skips its updates of the state that are not
 * idempotent). Where the seed overflowed, the host starts again from the seed. For the
 * host's statistics and its next batch, counts[4] and counts[5] add up the items of all
 * rounds (low and high word), counts[6] keeps the largest round and counts[7] the
 * number of rounds that had items.
 *
 * On a device that ends loops early (CS_LOOP_TRIPS, runtime/loop_trips.h) the host
 * launches each round over exactly its items, so a work-item makes only one item's
 * trips; a round kernel ends with cs_worklist_check_loops, which raises counts[8] if its
 * loops were cut short all the same (counts[9] holds 1) and the host stops. */
#include "loop_trips.h"

inline int cs_worklist_replay(__global const uint* counts, const uint round) { return counts[11] == round + 1; }

inline uint cs_worklist_items(__global uint* counts, const uint round, const uint capacity)
{
  const uint n = counts[round % 3];
  /* counts[10] is written only by a round that does nothing, so every work-item of a
   * round reads the same. */
  if (n > capacity || counts[10]) {
    if (get_global_id(0) == 0 && !counts[10]) counts[10] = round + 1;
    return 0;
  }
  if (get_global_id(0) == 0) {
    counts[(round + 2) % 3] = 0;
    if (!cs_worklist_replay(counts, round)) {
      const uint low = counts[4] + n;
      if (low < n) ++counts[5];
      counts[4] = low;
      counts[6] = max(counts[6], n);
      if (n) counts[7] = round + 1;
    }
  }
  return n;
}

/* One atomic a group on the global count: the group adds up its items first. */
inline uint cs_worklist_append(__local uint* group, __global uint* counts, const uint round, const uint k)
{
  barrier(CLK_LOCAL_MEM_FENCE); /* the last iteration's readers of group[1] are done */
  if (get_local_id(0) == 0) group[0] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint at = k ? atomic_add(&group[0], k) : 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) == 0) group[1] = group[0] ? atomic_add(&counts[(round + 1) % 3], group[0]) : 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  return group[1] + at;
}

inline int cs_worklist_fits(__global uint* counts, const uint capacity, const uint index)
{
  if (index < capacity) return 1;
  atomic_max(&counts[3], index + 1);
  return 0;
}

/* Every work-item of a seed over n inputs, before its first items. */
inline void cs_worklist_seed_begin(__global uint* counts, const uint n)
{
  if (get_global_id(0) == 0) {
    atomic_add(&counts[0], n);
    counts[9] = 1u;
  }
}

/* Where a seed over n inputs writes a first item beyond its input's own list[i]: an
 * index below the capacity, or the capacity itself where the list is full (the host
 * then grows it and starts again from the seed). */
inline uint cs_worklist_seed_index(__global uint* counts, const uint n, const uint capacity)
{
  atomic_inc(&counts[0]);
  const uint at = n + atomic_inc(&counts[12]);
  return cs_worklist_fits(counts, capacity, at) ? at : capacity;
}

inline void cs_worklist_check_loops(__global uint* counts, const uint round)
{
#if CS_LOOP_TRIPS
  if (cs_loops_were_cut(2u + (round == 0xffffffffu), counts + 9)) counts[8] = 1u;
#endif
}

#endif
