#ifndef CSTREAMS_RUNTIME_WORKLIST_H
#define CSTREAMS_RUNTIME_WORKLIST_H
/* The rounds of a work list (Worklist in runtime/stream_graph.hpp), as a round kernel
 * uses them:
 *
 *   __local uint group[2];
 *   uint first_items;
 *   const uint first = cs_worklist_first_round(counts, launch, &first_items);
 *   for (uint round = first;; ++round) {
 *     const uint n = cs_worklist_round_items(counts, launch, first, first_items, round, capacity, tail);
 *     if (n == 0) break;
 *     in = round % 2 ? list1 : list0, out the other;
 *     for (uint base = get_group_id(0) * get_local_size(0); base < n; base += get_global_size(0)) {
 *       const uint i = base + get_local_id(0);
 *       ... k: the items this work-item appends (none where i >= n)
 *       const uint at = cs_worklist_append(group, counts, round, k);  // every work-item of the group
 *       for (uint j = 0; j < k; ++j) if (cs_worklist_fits(counts, capacity, at + j)) out[at + j] = ...;
 *     }
 *     cs_worklist_round_end();
 *   }
 *   cs_worklist_check_loops(counts, first);
 *
 * counts[r % 3] holds the items of round r (a seed's extra first items add to
 * counts[0]). Round r appends to counts[(r + 1) % 3] and clears counts[(r + 2) % 3],
 * which round r - 1 read and round r + 1 appends to, so no launch is needed between
 * rounds. An append past the capacity writes nothing and raises counts[CS_LIST_NEEDED]
 * to the capacity it needed: the host grows the lists and starts the work again.
 *
 * The device numbers the rounds: launch j starts at the round in
 * counts[CS_LIST_ROUND + j % 2] and leaves the round after its last in the other word,
 * so a batch of launches needs no host round trip however many rounds each runs. A
 * launch with tail == 0 runs one round over all its groups. A tail launch is one group
 * that runs round after round, with a barrier between them, while a round has items and
 * at most `tail` of them: where a round is short, its launch and the chain of reads
 * before its first visit cost more than its work.
 *
 * For the host's statistics and its next batch, the two words at CS_LIST_ITEMS add up
 * the items of all rounds (low and high word); CS_LIST_WIDEST keeps the largest round,
 * CS_LIST_ROUNDS the number of rounds that had items, CS_LIST_TAIL_ROUNDS those that
 * ran in a tail, and counts[CS_LIST_LOG + r] the items of round r, for the first
 * CS_LIST_LOG_ROUNDS.
 *
 * On a device that ends loops early (CS_LOOP_TRIPS, runtime/loop_trips.h) the host
 * launches each round over exactly its items and no tail, so a work-item makes only
 * one item's trips; a round kernel ends with cs_worklist_check_loops, which raises
 * counts[CS_LIST_CUT] if its loops were cut short all the same (counts[CS_LIST_CANARY]
 * holds 1) and the host stops. Host twin of the layout: list_words and its neighbours
 * in runtime/src/scheduler.cpp. */
#include "loop_trips.h"

/* Words 0-2 and the round words lie in the first eight, which a launch reads at once. */
#define CS_LIST_ROUND 3u
#define CS_LIST_NEEDED 5u
#define CS_LIST_ITEMS 6u
#define CS_LIST_WIDEST 8u
#define CS_LIST_ROUNDS 9u
#define CS_LIST_CUT 10u
#define CS_LIST_CANARY 11u
#define CS_LIST_TAIL_ROUNDS 12u
#define CS_LIST_LOG 13u
#define CS_LIST_LOG_ROUNDS 64u
/* Rounds one tail launch runs at most, so that no launch runs unbounded. */
#define CS_LIST_TAIL_MOST 1024u

/* The round a launch starts at, and its items, in one read rather than a read of the
 * count that waits for the round number (on the H200 the difference is within the
 * noise of a ~12 us round). */
inline uint cs_worklist_first_round(__global const uint* counts, const uint launch, uint* items)
{
  const uint8 c = vload8(0, counts);
  const uint round = launch % 2u ? c.s4 : c.s3;
  const uint k = round % 3u;
  *items = k == 0u ? c.s0 : k == 1u ? c.s1 : c.s2;
  return round;
}

/* The items of `round` for this launch to run, at most the capacity; 0 where the launch
 * runs no more rounds, after its first work-item has told the next launch where to
 * start. A tail launch (tail > 0: the most items of a round it runs) is one group; a
 * launch of one round reads no count after it. */
inline uint cs_worklist_round_items(__global uint* counts, const uint launch, const uint first, const uint first_items,
                                    const uint round, const uint capacity, const uint tail)
{
  const uint n = round == first ? first_items
                 : tail && get_group_id(0) == 0 && round - first < CS_LIST_TAIL_MOST ? counts[round % 3]
                                                                                     : 0u;
  const int runs = n > 0 && (tail ? get_group_id(0) == 0 && n <= tail : round == first);
  if (get_global_id(0) == 0) {
    if (!runs) {
      counts[CS_LIST_ROUND + (launch + 1u) % 2u] = round;
    } else {
      counts[(round + 2) % 3] = 0;
      const uint low = counts[CS_LIST_ITEMS] + n;
      if (low < n) ++counts[CS_LIST_ITEMS + 1];
      counts[CS_LIST_ITEMS] = low;
      counts[CS_LIST_WIDEST] = max(counts[CS_LIST_WIDEST], n);
      counts[CS_LIST_ROUNDS] = round + 1;
      if (tail) ++counts[CS_LIST_TAIL_ROUNDS];
      if (round < CS_LIST_LOG_ROUNDS) counts[CS_LIST_LOG + round] = n;
    }
  }
  return runs ? min(n, capacity) : 0u;
}

/* Between the rounds of a tail launch, its appends, counts and whatever state the round
 * wrote are seen by the whole group. */
inline void cs_worklist_round_end(void) { barrier(CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE); }

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
  atomic_max(&counts[CS_LIST_NEEDED], index + 1);
  return 0;
}

/* Where a seed writes a first item beyond its input's own list[i]: an index below the
 * capacity, or the capacity itself where the list is full (the host then grows it and
 * starts again, as after a round's overflow). */
inline uint cs_worklist_seed_index(__global uint* counts, const uint capacity)
{
  const uint at = atomic_inc(&counts[0]);
  return cs_worklist_fits(counts, capacity, at) ? at : capacity;
}

inline void cs_worklist_check_loops(__global uint* counts, const uint first)
{
#if CS_LOOP_TRIPS
  if (cs_loops_were_cut(2u + (first == 0xffffffffu), counts + CS_LIST_CANARY)) counts[CS_LIST_CUT] = 1u;
#endif
}

#endif
