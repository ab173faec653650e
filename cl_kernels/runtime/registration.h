#ifndef CSTREAMS_RUNTIME_REGISTRATION_H
#define CSTREAMS_RUNTIME_REGISTRATION_H
/* Stream registration: how a kernel emits a variable number of items into a stream.
 *
 *   __kernel void k(..., CS_EMITTER_PARAMS(uint2, pairs)) {
 *     CS_EMITTER_BEGIN(pairs);          // at kernel scope, before any early return
 *     if (get_global_id(0) < n) { ... CS_EMIT(pairs, (uint2)(a, b)); ... }
 *     CS_EMITTER_END(pairs);            // reached by every work-item
 *   }
 *
 * The scheduler builds the program with CS_REGISTRATION set to one of the modes below,
 * appends the nine emitter arguments per emitted stream, launches with CS_WG_SIZE
 * work-items per group and packs the result:
 *   CS_REG_GLOBAL_ATOMIC   one device counter for the whole stream (the baseline);
 *   CS_REG_SEGMENTED_LOCK  a segment per work-group claimed through a local counter,
 *                          then prefix sum and merge (the paper's segmented lock).
 *                          Segments are planned from the last run: group g's segment
 *                          holds what group g emitted then and an eighth more
 *                          (cs_segment_base below), so memory follows the work where
 *                          it is, not the busiest group. What a segment cannot hold
 *                          goes to a spill pool of P_pool items shared by all groups
 *                          through the overflow slot, with its group and rank, so
 *                          that the merge still puts it in order (the scheduler sizes
 *                          the pool by what spilled in the last run);
 *   CS_REG_LOCK_FREE       a segment per work-item with a private counter, then
 *                          prefix sum and merge (the paper's lock-free variant).
 * Counters keep counting past capacity, so the host learns what to grow to: a lock-free
 * segment that overflows raises its pass's overflow slot to its count; with segmented
 * locks the slot counts the items spilled, and a pool too small reruns the pass
 * planned from that run's counts. */
#include "common.h"

#define CS_REG_GLOBAL_ATOMIC 0
#define CS_REG_SEGMENTED_LOCK 1
#define CS_REG_LOCK_FREE 2

/* Segmented lock: where group g's segment starts, given the last run's segment offsets
 * `plan` (planned groups, then their total). A group the last run had gets what it
 * emitted then and an eighth more (with a quarter, n-body's settled step held 10 MiB
 * more at its peak); a group it did not have gets `fresh`. The spill
 * pool follows the last group's segment. The scheduler sizes the buffer by the same
 * rules (SegmentPlanner::segment_items, runtime/src/scheduler/segment_plan.cpp). */
inline uint cs_segment_base(__global const uint* plan, const uint planned, const uint fresh, const uint g)
{
  const uint k = min(g, planned), o = plan[k];
  return o + o / 8u + (g - k) * fresh;
}

#define CS_EMITTER_PARAMS(T, P)                                                               \
  __global T* P##_out, __global uint* P##_counts, const uint P##_capacity,                    \
      __global uint* P##_counters, const uint P##_slot, __global const uint* P##_plan,        \
      const uint P##_planned, const uint P##_pool, const uint P##_total_slot

#if !defined(CS_REGISTRATION)
/* Built outside a scheduler: any use of an emitter fails to compile with this name
 * (an undeclared identifier is a compile error everywhere; an undeclared function
 * only fails at link time on some drivers, with a vaguer message). */
#define CS_EMITTER_BEGIN(P) (void)cs_registration_mode_is_set_by_the_scheduler
#define CS_EMIT(P, value) (void)cs_registration_mode_is_set_by_the_scheduler
#define CS_EMITTER_END(P) (void)cs_registration_mode_is_set_by_the_scheduler

#elif CS_REGISTRATION == CS_REG_GLOBAL_ATOMIC
#define CS_EMITTER_BEGIN(P) (void)P##_counts
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    const uint cs_at_ = atomic_inc(&P##_counters[P##_slot]);                                  \
    if (cs_at_ < P##_capacity) P##_out[cs_at_] = (value);                                     \
  } while (0)
#define CS_EMITTER_END(P) (void)0

#elif CS_REGISTRATION == CS_REG_SEGMENTED_LOCK
/* P_plan holds the last run's P_planned + 1 segment offsets (the exclusive prefix sum of
 * its group counts, then their total); P_capacity is the room of a group it did not
 * have. P_counts holds each group's count, then (group, rank) of each spilled item. The
 * overflow slot counts spilled items, past the pool's size too; the total slot, the
 * stream's count, adds up the groups' counts, so that the host learns it with the
 * stage's counters before anything has scanned the counts (the merge of an output
 * packed after that read then finds its offsets itself, compact.cl). A group that
 * finds the pool full stops asking the overflow slot for places and adds what it spilled
 * past them at its end: a first step searched from the roots spills millions of items,
 * and their atomics on one word took a twentieth of its front update (H200, cold step's
 * front update: cloth-ball 4.89 -> 4.65 ms, n-body 7.20 -> 7.01). The group's segment
 * (start, room, spill pool's start) sits in local memory: read from the plan at each
 * emit, the compiler would load it early and hold it in registers through the kernel. */
#define CS_EMITTER_BEGIN(P)                                                                   \
  __local uint P##_group_count, P##_segment[3], P##_pool_tries, P##_pool_full;                \
  if (get_local_id(0) == 0) {                                                                 \
    const uint cs_g_ = (uint)get_group_id(0);                                                 \
    P##_group_count = 0;                                                                      \
    P##_pool_tries = 0;                                                                       \
    P##_pool_full = 0;                                                                        \
    P##_segment[0] = cs_segment_base(P##_plan, P##_planned, P##_capacity, cs_g_);             \
    P##_segment[1] = cs_segment_base(P##_plan, P##_planned, P##_capacity, cs_g_ + 1u) - P##_segment[0]; \
    P##_segment[2] = cs_segment_base(P##_plan, P##_planned, P##_capacity, (uint)get_num_groups(0)); \
  }                                                                                           \
  barrier(CLK_LOCAL_MEM_FENCE)
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    const uint cs_at_ = atomic_inc(&P##_group_count);                                         \
    if (cs_at_ < P##_segment[1]) {                                                            \
      P##_out[P##_segment[0] + cs_at_] = (value);                                             \
    } else if (!P##_pool_full) {                                                              \
      const uint cs_groups_ = (uint)get_num_groups(0);                                        \
      const uint cs_spill_ = atomic_inc(&P##_counters[P##_slot]);                             \
      atomic_inc(&P##_pool_tries);                                                            \
      if (cs_spill_ < P##_pool) {                                                             \
        P##_out[P##_segment[2] + cs_spill_] = (value);                                        \
        P##_counts[cs_groups_ + 2u * cs_spill_] = (uint)get_group_id(0);                      \
        P##_counts[cs_groups_ + 2u * cs_spill_ + 1u] = cs_at_;                                \
      } else {                                                                                \
        P##_pool_full = 1u;                                                                   \
      }                                                                                       \
    }                                                                                         \
  } while (0)
#define CS_EMITTER_END(P)                                                                     \
  barrier(CLK_LOCAL_MEM_FENCE);                                                               \
  if (get_local_id(0) == 0) {                                                                 \
    P##_counts[get_group_id(0)] = P##_group_count;                                            \
    if (P##_group_count) atomic_add(&P##_counters[P##_total_slot], P##_group_count);          \
    const uint cs_spilled_ = P##_group_count - min(P##_group_count, P##_segment[1]);          \
    if (cs_spilled_ > P##_pool_tries)                                                         \
      atomic_add(&P##_counters[P##_slot], cs_spilled_ - P##_pool_tries);                      \
  }

#elif CS_REGISTRATION == CS_REG_LOCK_FREE
#define CS_EMITTER_BEGIN(P) uint P##_count = 0
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    if (P##_count < P##_capacity)                                                             \
      P##_out[(size_t)P##_count * get_global_size(0) + get_global_id(0)] = (value);           \
    ++P##_count;                                                                              \
  } while (0)
#define CS_EMITTER_END(P)                                                                     \
  P##_counts[get_global_id(0)] = P##_count;                                                   \
  if (P##_count > P##_capacity) atomic_max(&P##_counters[P##_slot], P##_count)

#else
#error "unknown CS_REGISTRATION"
#endif

#endif
