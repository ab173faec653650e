#ifndef CSTREAMS_CCD_REFINE_EARLIEST_H
#define CSTREAMS_CCD_REFINE_EARLIEST_H
/* refine.cl in a step that reports only each object's earliest time: the queries that
 * can no longer hold one are given up (refine.cl's opening comment says when). */
#include "conservative.h"
#include "refine_state.h"

/* Built with CS_EARLIEST_ACROSS (a scene of objects): whether this step reports only
 * each object's earliest time, every vertex's object, and two words per object: the
 * earliest contact any query has found so far, as the bits of a float rounded up (a
 * contact's time, not yet an answer: the answer of the query that found it is no
 * later), and the first round that found a contact at time 0 (0xffffffff: none). */
#if CS_EARLIEST_ACROSS
#define CS_EARLIEST_PARAMS , const uint earliest_only, __global const uint *vertex_object, __global uint *found
#else
#define CS_EARLIEST_PARAMS
#endif

#if CS_EARLIEST_ACROSS
/* Built so, the state of the n queries is followed by three words a query, held only
 * while earliest_only is set (Worklist::extra_state_bytes): first[r % 3] is the earliest
 * start of round r's boxes as a float rounded down, gathered by round r - 1 as work[]
 * is. Apart from the rest, so that steps that need no earliest time read the state as
 * they would without it, and hold no memory for it. */
inline __global uint* cs_first_starts(__global cs_refine_state* state, const uint n, const uint query)
{
  return (__global uint*)(state + n) + 3 * query;
}

inline uint2 cs_query_objects(const cs_refine_state* s, __global const uint* vertex_object)
{
  return (uint2)(vertex_object[s->vertices[0]], vertex_object[s->vertices[s->flags & CS_FLAG_VERTEX_FACE ? 1 : 2]]);
}

/* Whether the query's answer can no longer be an object's earliest time that another
 * query does not give. Its answer is no earlier than `bound`: its earliest contact so
 * far or its earliest box left, moved back by the tolerance (cs_final_time).
 * - Where the bound is later than a contact found for the object, so is the answer:
 *   the query that found the contact answers no later than it, and goes on (its own
 *   bound is no later than its contact, so it never gives itself up).
 * - Where a round before this one found a contact at 0 for the object, its query
 *   answers 0, and answers can be no earlier. That query goes on: from then on its
 *   earliest contact so far (`before`) is 0, and such a query never gives up here. */
inline int cs_covered(__global const uint* found, const uint object, const real bound, const real before,
                      const uint round)
{
  return bound > (real)as_float(found[2 * object]) || (before > 0 && found[2 * object + 1] < round);
}

inline int cs_not_earliest(const cs_refine_state* seen, __global const uint* first, const uint round,
                           const real before, const real tolerance, __global const uint* vertex_object,
                           __global const uint* found)
{
  if (seen->flags & CS_FLAG_NOT_EARLIEST) return 1;
  const real bound = cs_final_time(fmin(before, (real)as_float(first[(round + 2) % 3])), 1, tolerance);
  if (!(bound > 0) && !(before > 0)) return 0;
  const uint2 o = cs_query_objects(seen, vertex_object);
  return cs_covered(found, o.x, bound, before, round) && cs_covered(found, o.y, bound, before, round);
}

inline void cs_found_at(volatile __global uint* found, const uint object, const uint key, const uint round)
{
  if (key < found[2 * object]) atomic_min(&found[2 * object], key);
  if (key == 0 && round < found[2 * object + 1]) atomic_min(&found[2 * object + 1], round);
}
#endif

#if CS_EARLIEST_ACROSS
/* Before any round, and again when the list overflowed and the search starts over:
 * contacts found by a cut-short search must not give up queries. Every store is the
 * same value; the test keeps most of them off the few objects' words. `first_start`:
 * round 0's first box's start. */
inline void cs_seed_earliest(__global uint* first, const uint first_start, const uint2 o, __global uint* found)
{
  first[0] = first[1] = CS_NO_TIME;
  first[2] = first_start;
  for (int k = 0; k < 2; ++k) {
    const uint object = k ? o.y : o.x;
    if (found[2 * object] != CS_NO_TIME) found[2 * object] = CS_NO_TIME;
    if (found[2 * object + 1] != 0xffffffffu) found[2 * object + 1] = 0xffffffffu;
  }
}
#endif

#if CS_EARLIEST_ACROSS
/* In earliest-only mode, after a visit: the next round's first start reset, the first
 * start of the boxes it leaves (lo, or the one cut, starts no later), and a contact's
 * time for its objects (with CS_ESCALATE, a proven one's end of proof). */
inline void cs_round_earliest(__global uint* first, const uint round, const int visit, const real lo_start,
                              const real t, const real proven_end, const cs_refine_state* seen,
                              __global const uint* vertex_object, volatile __global uint* found)
{
  first[(round + 1) % 3] = CS_NO_TIME;
  if (visit >= CS_BOX_SPLIT) {
    const uint start = cs_float_key_down(lo_start);
    if (start < first[round % 3]) atomic_min(&first[round % 3], start);
  }
#if CS_ESCALATE
  const real contact = proven_end;
  (void)t;
#else
  const real contact = t;
  (void)proven_end;
#endif
  if (visit == CS_BOX_HIT && contact <= 1) {
    const uint2 o = cs_query_objects(seen, vertex_object);
    const uint key = cs_float_key_up(contact);
    cs_found_at(found, o.x, key, round);
    cs_found_at(found, o.y, key, round);
  }
}
#endif

#endif
