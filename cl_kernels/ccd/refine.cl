/* Refinement of the pairs the conservative screen left open (narrow_phase_pairs.cl).
 * Built with CS_REAL_DOUBLE, CS_STACK_SIZE and, by the scheduler, CS_REGISTRATION and
 * CS_WG_SIZE (the work-group size it launches with, chosen per device).
 *
 * cs_refine_breadth_first spreads each query's boxes over a work-group. The group holds
 * several queries at once, each with a fixed number of box positions; a round visits
 * every live box with one work-item each, and the halves of the boxes refined take
 * their places for the next round. The earliest contact found in a round prunes from
 * the next round on, so a query's answer depends on nothing but the query: not on the
 * device, the group, or the queries beside it. A query whose boxes outgrow its
 * positions is emitted as unfinished and starts over where there are more (fewer
 * queries a group, then one, then the depth-first search of cs_refine_depth_first);
 * none is dropped.
 * Groups take queries group id, group id + groups, ..., so no launch size matters
 * beyond speed. */
#include "conservative.h"
#include "pairs.h"
#include "runtime/registration.h"

#define CS_NO_QUERY 0xffffffffu
/* Box positions of a group, however many work-items it has: each work-item holds
 * CS_PER_ITEM of them, so the search (and its answer) is the same on a device that
 * runs 32 work-items a group as on one that runs 256. */
#define CS_POSITIONS 256u
#if CS_WG_SIZE > 256 || 256 % CS_WG_SIZE != 0
#error "cs_refine_breadth_first needs a power-of-two work-group size of at most 256"
#endif
#define CS_PER_ITEM (CS_POSITIONS / CS_WG_SIZE)
#define CS_MAX_SLOTS (CS_POSITIONS / 8u)
#define CS_FLAG_SLACK 1u
#define CS_FLAG_LIMIT 2u
#define CS_FLAG_OVERFLOW 4u
#define CS_FLAG_HIT 8u

/* positions: box positions a query holds (a power of two; 0 or CS_POSITIONS and more:
 * all of them, one query a group at a time). */
__kernel void cs_refine_breadth_first(__global const uint2* pairs, const uint n, const uint vertex_face,
                                      __global const real* x0, __global const real* x1, __global const uint* faces,
                                      __global const uint* edges, const uint exact_input, const real tolerance,
                                      const real separation, const uint max_iterations, const uint positions,
                                      CS_EMITTER_PARAMS(uint4, contacts), CS_EMITTER_PARAMS(uint2, unfinished))
{
  __local cs_box box[CS_POSITIONS];
  __local real hit[CS_POSITIONS];
  __local cs_trilinear function[CS_MAX_SLOTS];
  __local real tol[CS_MAX_SLOTS], best[CS_MAX_SLOTS];
  __local uint query[CS_MAX_SLOTS], count[CS_MAX_SLOTS], next_count[CS_MAX_SLOTS], flags[CS_MAX_SLOTS],
      work[CS_MAX_SLOTS];
  __local uint next_query;
  CS_EMITTER_BEGIN(contacts);
  CS_EMITTER_BEGIN(unfinished);
  const uint lid = get_local_id(0);
  const uint cap = positions == 0 || positions >= CS_POSITIONS ? CS_POSITIONS : max(positions, CS_POSITIONS / CS_MAX_SLOTS);
  const uint slots = CS_POSITIONS / cap;
  if (lid == 0) next_query = get_group_id(0);
  for (uint sl = lid; sl < slots; sl += CS_WG_SIZE) {
    query[sl] = CS_NO_QUERY;
    count[sl] = 0;
    next_count[sl] = 0;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (;;) {
    /* Free slots take the group's next queries. */
    for (uint sl = lid; sl < slots; sl += CS_WG_SIZE) {
      if (query[sl] != CS_NO_QUERY) continue;
      const uint qi = atomic_add(&next_query, get_num_groups(0));
      if (qi < n) {
        const cs_query q = cs_pair_query(pairs[qi], vertex_face, x0, x1, faces, edges, exact_input);
        query[sl] = qi;
        function[sl] = cs_make_trilinear(&q, (int)vertex_face);
        tol[sl] = tolerance * cs_query_scale(&q);
        best[sl] = 2;
        flags[sl] = 0;
        work[sl] = 0;
        box[sl * cap] = cs_root_box();
        count[sl] = 1;
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    uint live = 0;
    for (uint s = 0; s < slots; ++s) live |= count[s];
    if (live == 0) break;

    /* One box a position. */
    int visit[CS_PER_ITEM];
    uint at[CS_PER_ITEM];
    cs_box lo[CS_PER_ITEM], hi[CS_PER_ITEM];
    for (uint k = 0; k < CS_PER_ITEM; ++k) {
      const uint p = lid + k * CS_WG_SIZE, s = p / cap, j = p % cap;
      visit[k] = CS_BOX_DROP;
      at[k] = 0;
      if (j < count[s]) {
        const cs_trilinear f = function[s];
        int slack = 0, limited = 0;
        real t;
        visit[k] = cs_visit_box(&f, box[p], (int)vertex_face, tol[s], tolerance, separation, best[s],
                                work[s] >= max_iterations, &slack, &limited, &t, &lo[k], &hi[k]);
        hit[p] = visit[k] == CS_BOX_HIT ? t : (real)2;
        if (slack) atomic_or(&flags[s], CS_FLAG_SLACK);
        if (limited) atomic_or(&flags[s], CS_FLAG_LIMIT);
        if (visit[k] == CS_BOX_HIT) atomic_or(&flags[s], CS_FLAG_HIT);
      }
      if (visit[k] == CS_BOX_SPLIT) {
        at[k] = atomic_add(&next_count[s], 2u);
        if (at[k] + 2 > cap) atomic_or(&flags[s], CS_FLAG_OVERFLOW);
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE); /* every box of this round read */
    for (uint k = 0; k < CS_PER_ITEM; ++k) {
      const uint s = (lid + k * CS_WG_SIZE) / cap;
      if (visit[k] == CS_BOX_SPLIT && at[k] + 2 <= cap) {
        box[s * cap + at[k]] = lo[k];
        box[s * cap + at[k] + 1] = hi[k];
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    /* Each slot folds its round in: the earliest contact, and whether it is done. */
    for (uint sl = lid; sl < slots; sl += CS_WG_SIZE) {
      if (query[sl] == CS_NO_QUERY) continue;
      const uint q = query[sl];
      uint f = flags[sl];
      if (f & CS_FLAG_HIT) {
        real b = best[sl];
        for (uint i = 0; i < count[sl]; ++i) b = fmin(b, hit[sl * cap + i]);
        best[sl] = b;
        f &= ~CS_FLAG_HIT;
      }
      const uint children = next_count[sl];
      next_count[sl] = 0;
      work[sl] += children / 2;
      int done = children == 0;
      if (f & CS_FLAG_OVERFLOW) {
        CS_EMIT(unfinished, pairs[q]);
        done = 1;
      } else if (done) {
        const uint status = (f & CS_FLAG_LIMIT) ? CS_LIMIT : best[sl] <= 1 ? CS_COLLIDES : CS_SEPARATE;
        if (status != CS_SEPARATE)
          CS_EMIT(contacts, cs_contact(pairs[q], cs_final_time(best[sl], f & CS_FLAG_SLACK, tolerance), status));
      }
      flags[sl] = f;
      count[sl] = done ? 0 : children;
      if (done) query[sl] = CS_NO_QUERY;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  CS_EMITTER_END(contacts);
  CS_EMITTER_END(unfinished);
}

/* The queries too wide for a work-group: the depth-first search, one work-item each. */
__kernel void cs_refine_depth_first(__global const uint2* pairs, const uint n, const uint vertex_face,
                                    __global const real* x0, __global const real* x1, __global const uint* faces,
                                    __global const uint* edges, const uint exact_input, const real tolerance,
                                    const real separation, const uint max_iterations,
                                    CS_EMITTER_PARAMS(uint4, contacts))
{
  CS_EMITTER_BEGIN(contacts);
  const uint i = get_global_id(0);
  if (i < n) {
    const cs_query q = cs_pair_query(pairs[i], vertex_face, x0, x1, faces, edges, exact_input);
    real t;
    const uint s = cs_conservative(&q, (int)vertex_face, tolerance, separation, max_iterations, &t);
    if (s != CS_SEPARATE) CS_EMIT(contacts, cs_contact(pairs[i], t, s));
  }
  CS_EMITTER_END(contacts);
}
