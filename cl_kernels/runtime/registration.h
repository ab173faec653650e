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
 * appends the seven emitter arguments per emitted stream, launches with CS_WG_SIZE
 * work-items per group and packs the result:
 *   CS_REG_GLOBAL_ATOMIC   one device counter for the whole stream (the baseline);
 *   CS_REG_SEGMENTED_LOCK  a segment per work-group claimed through a local counter,
 *                          then prefix sum and merge (the paper's segmented lock);
 *   CS_REG_LOCK_FREE       a segment per work-item with a private counter, then
 *                          prefix sum and merge (the paper's lock-free variant).
 * Segments are sized for the average segment of the last run, not the busiest: what a
 * busier segment cannot hold spills through one device counter (the slot) straight
 * into the front of the stream (dst), and the merge places the segments after the
 * spilled items. So scratch memory follows the work there is, and a burst costs
 * atomics rather than memory. Counters keep counting past capacity, so the host
 * learns the capacity it must grow the stream to. */
#include "common.h"

#define CS_REG_GLOBAL_ATOMIC 0
#define CS_REG_SEGMENTED_LOCK 1
#define CS_REG_LOCK_FREE 2

#define CS_EMITTER_PARAMS(T, P)                                                               \
  __global T* P##_out, __global uint* P##_counts, const uint P##_capacity,                    \
      __global uint* P##_counters, const uint P##_slot, __global T* P##_dst, const uint P##_dst_capacity

#if !defined(CS_REGISTRATION)
/* Built outside a scheduler: any use of an emitter fails to compile with this name
 * (an undeclared identifier is a compile error everywhere; an undeclared function
 * only fails at link time on some drivers, with a vaguer message). */
#define CS_EMITTER_BEGIN(P) (void)cs_registration_mode_is_set_by_the_scheduler
#define CS_EMIT(P, value) (void)cs_registration_mode_is_set_by_the_scheduler
#define CS_EMITTER_END(P) (void)cs_registration_mode_is_set_by_the_scheduler

#elif CS_REGISTRATION == CS_REG_GLOBAL_ATOMIC
#define CS_EMITTER_BEGIN(P) (void)P##_counts, (void)P##_dst, (void)P##_dst_capacity
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    const uint cs_at_ = atomic_inc(&P##_counters[P##_slot]);                                  \
    if (cs_at_ < P##_capacity) P##_out[cs_at_] = (value);                                     \
  } while (0)
#define CS_EMITTER_END(P) (void)0

#elif CS_REGISTRATION == CS_REG_SEGMENTED_LOCK || CS_REGISTRATION == CS_REG_LOCK_FREE
/* What a full segment cannot hold. */
#define CS_SPILL(P, value)                                                                    \
  do {                                                                                        \
    const uint cs_spill_ = atomic_inc(&P##_counters[P##_slot]);                               \
    if (cs_spill_ < P##_dst_capacity) P##_dst[cs_spill_] = (value);                           \
  } while (0)

#if CS_REGISTRATION == CS_REG_SEGMENTED_LOCK
#define CS_EMITTER_BEGIN(P)                                                                   \
  __local uint P##_group_count;                                                               \
  if (get_local_id(0) == 0) P##_group_count = 0;                                              \
  barrier(CLK_LOCAL_MEM_FENCE)
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    const uint cs_at_ = atomic_inc(&P##_group_count);                                         \
    if (cs_at_ < P##_capacity) P##_out[(size_t)get_group_id(0) * P##_capacity + cs_at_] = (value); \
    else CS_SPILL(P, value);                                                                  \
  } while (0)
#define CS_EMITTER_END(P)                                                                     \
  barrier(CLK_LOCAL_MEM_FENCE);                                                               \
  if (get_local_id(0) == 0) P##_counts[get_group_id(0)] = min(P##_group_count, P##_capacity)

#else
#define CS_EMITTER_BEGIN(P) uint P##_count = 0
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    if (P##_count < P##_capacity) {                                                           \
      P##_out[(size_t)P##_count * get_global_size(0) + get_global_id(0)] = (value);           \
      ++P##_count;                                                                            \
    } else {                                                                                  \
      CS_SPILL(P, value);                                                                     \
    }                                                                                         \
  } while (0)
#define CS_EMITTER_END(P) P##_counts[get_global_id(0)] = P##_count
#endif

#else
#error "unknown CS_REGISTRATION"
#endif

#endif
