/* Refinement of the pairs the conservative screen left open (narrow_phase_pairs.cl).
 * Built with CS_REAL_DOUBLE, CS_STACK_SIZE and, by the scheduler, CS_REGISTRATION and
 * CS_WG_SIZE (the work-group size it launches with).
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
#define CS_MAX_SLOTS (CS_WG_SIZE >= 8 ? CS_WG_SIZE / 8 : 1)
#define CS_FLAG_SLACK 1u
#define CS_FLAG_LIMIT 2u
#define CS_FLAG_OVERFLOW 4u
#define CS_FLAG_HIT 8u

/* positions: box positions a query holds (a power of two; 0 or CS_WG_SIZE and more: the
 * whole group, one query at a time). */
__kernel void cs_refine_breadth_first(__global const uint2* pairs, const uint n, const uint vertex_face,
                                      __global const real* x0, __global const real* x1, __global const uint* faces,
                                      __global const uint* edges, const uint exact_input, const real tolerance,
                                      const real separation, const uint max_iterations, const uint positions,
                                      CS_EMITTER_PARAMS(uint4, contacts), CS_EMITTER_PARAMS(uint2, unfinished))
{
  __local cs_box box[CS_WG_SIZE];
  __local real hit[CS_WG_SIZE];
  __local cs_trilinear function[CS_MAX_SLOTS];
  __local real tol[CS_MAX_SLOTS], best[CS_MAX_SLOTS];
  __local uint query[CS_MAX_SLOTS], count[CS_MAX_SLOTS], next_count[CS_MAX_SLOTS], flags[CS_MAX_SLOTS],
      work[CS_MAX_SLOTS];
  __local uint next_query;
  CS_EMITTER_BEGIN(contacts);
  CS_EMITTER_BEGIN(unfinished);
  const uint lid = get_local_id(0);
  const uint cap = positions == 0 || positions >= CS_WG_SIZE ? CS_WG_SIZE : max(positions, (uint)(CS_WG_SIZE / CS_MAX_SLOTS));
  const uint slots = CS_WG_SIZE / cap;
  if (lid == 0) next_query = get_group_id(0);
  if (lid < slots) {
    query[lid] = CS_NO_QUERY;
    count[lid] = 0;
    next_count[lid] = 0;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (;;) {
    /* Free slots take the group's next queries. */
    if (lid < slots && query[lid] == CS_NO_QUERY) {
      const uint qi = atomic_add(&next_query, get_num_groups(0));
      if (qi < n) {
        const cs_query q = cs_pair_query(pairs[qi], vertex_face, x0, x1, faces, edges, exact_input);
        query[lid] = qi;
        function[lid] = cs_make_trilinear(&q, (int)vertex_face);
        tol[lid] = tolerance * cs_query_scale(&q);
        best[lid] = 2;
        flags[lid] = 0;
        work[lid] = 0;
        box[lid * cap] = cs_root_box();
        count[lid] = 1;
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    uint live = 0;
    for (uint s = 0; s < slots; ++s) live |= count[s];
    if (live == 0) break;

    /* One box a work-item. */
    const uint s = lid / cap, j = lid % cap;
    int visit = CS_BOX_DROP;
    cs_box lo, hi;
    if (j < count[s]) {
      const cs_trilinear f = function[s];
      int slack = 0, limited = 0;
      real t;
      visit = cs_visit_box(&f, box[lid], (int)vertex_face, tol[s], tolerance, separation, best[s],
                           work[s] >= max_iterations, &slack, &limited, &t, &lo, &hi);
      hit[lid] = visit == CS_BOX_HIT ? t : (real)2;
      if (slack) atomic_or(&flags[s], CS_FLAG_SLACK);
      if (limited) atomic_or(&flags[s], CS_FLAG_LIMIT);
      if (visit == CS_BOX_HIT) atomic_or(&flags[s], CS_FLAG_HIT);
    }
    uint at = 0;
    if (visit == CS_BOX_SPLIT) {
      at = atomic_add(&next_count[s], 2u);
      if (at + 2 > cap) atomic_or(&flags[s], CS_FLAG_OVERFLOW);
    }
    barrier(CLK_LOCAL_MEM_FENCE); /* every box of this round read */
    if (visit == CS_BOX_SPLIT && at + 2 <= cap) {
      box[s * cap + at] = lo;
      box[s * cap + at + 1] = hi;
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    /* Each slot folds its round in: the earliest contact, and whether it is done. */
    if (lid < slots && query[lid] != CS_NO_QUERY) {
      const uint q = query[lid];
      uint f = flags[lid];
      if (f & CS_FLAG_HIT) {
        real b = best[lid];
        for (uint i = 0; i < count[lid]; ++i) b = fmin(b, hit[lid * cap + i]);
        best[lid] = b;
        f &= ~CS_FLAG_HIT;
      }
      const uint children = next_count[lid];
      next_count[lid] = 0;
      work[lid] += children / 2;
      int done = children == 0;
      if (f & CS_FLAG_OVERFLOW) {
        CS_EMIT(unfinished, pairs[q]);
        done = 1;
      } else if (done) {
        const uint status = (f & CS_FLAG_LIMIT) ? CS_LIMIT : best[lid] <= 1 ? CS_COLLIDES : CS_SEPARATE;
        if (status != CS_SEPARATE)
          CS_EMIT(contacts, cs_contact(pairs[q], cs_final_time(best[lid], f & CS_FLAG_SLACK, tolerance), status));
      }
      flags[lid] = f;
      count[lid] = done ? 0 : children;
      if (done) query[lid] = CS_NO_QUERY;
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
