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
 * appends the five emitter arguments per emitted stream, launches with CS_WG_SIZE
 * work-items per group and packs the result:
 *   CS_REG_GLOBAL_ATOMIC   one device counter for the whole stream (the baseline);
 *   CS_REG_SEGMENTED_LOCK  a segment per work-group claimed through a local counter,
 *                          then prefix sum and merge (the paper's segmented lock);
 *   CS_REG_LOCK_FREE       a segment per work-item with a private counter, then
 *                          prefix sum and merge (the paper's lock-free variant).
 * Counters keep counting past capacity; an overflowing segment also raises its pass's
 * overflow slot to its count, so the host learns the capacity it must grow to. With
 * segmented locks every work-group raises it (one atomic a group), so the host also
 * learns when segments sized for an earlier burst have become far too large. */
#include "common.h"

#define CS_REG_GLOBAL_ATOMIC 0
#define CS_REG_SEGMENTED_LOCK 1
#define CS_REG_LOCK_FREE 2

#define CS_EMITTER_PARAMS(T, P)                                                               \
  __global T* P##_out, __global uint* P##_counts, const uint P##_capacity,                    \
      __global uint* P##_counters, const uint P##_slot

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
#define CS_EMITTER_BEGIN(P)                                                                   \
  __local uint P##_group_count;                                                               \
  if (get_local_id(0) == 0) P##_group_count = 0;                                              \
  barrier(CLK_LOCAL_MEM_FENCE)
#define CS_EMIT(P, value)                                                                     \
  do {                                                                                        \
    const uint cs_at_ = atomic_inc(&P##_group_count);                                         \
    if (cs_at_ < P##_capacity) P##_out[(size_t)get_group_id(0) * P##_capacity + cs_at_] = (value); \
  } while (0)
#define CS_EMITTER_END(P)                                                                     \
  barrier(CLK_LOCAL_MEM_FENCE);                                                               \
  if (get_local_id(0) == 0) {                                                                 \
    P##_counts[get_group_id(0)] = P##_group_count;                                            \
    atomic_max(&P##_counters[P##_slot], P##_group_count);                                     \
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
