/* Refinement of the pairs the conservative screen left open (narrow_phase_pairs.cl),
 * breadth first across the whole device: a work list (runtime/worklist.h) of
 * (query, box) items, one box a work-item each round, so one hard query's boxes spread
 * over as many work-items as it has boxes and no query holds the others up.
 * Built with CS_REAL_DOUBLE and, by the scheduler, CS_REGISTRATION.
 *
 * Without a minimum separation, a query's first boxes span only the times at which its
 * four points may be coplanar (coplanarity.h): every contact is among them, so the
 * rounds no longer prove, box by box, that nothing touches before the first of them.
 *
 * Rounds are synchronous per query: round r prunes with the earliest contact of rounds
 * before r and checks the work of rounds before r, never with what round r itself
 * finds. So a query's answer depends on nothing but the query: not on the device, the
 * launch size, the order of the list, the queries beside it or the list's capacity (a
 * round that overflowed runs again as a replay, runtime/worklist.h, which adds no
 * splits twice and reads what the round read the first time). The state keeps both
 * halves of that: best[r % 2] gathers the earliest contact through round r while
 * round r reads best[(r + 1) % 2]; work[r % 3] counts round r's splits, and each item
 * carries its query's splits up to two rounds before.
 *
 * Where a step reports only each object's earliest time (earliest_only), a query that
 * can no longer hold its objects' earliest one is given up whole: its answer would
 * have been no earlier than a contact another query has found for each of its
 * objects. The queries that go on run exactly as they would have, so every object's
 * earliest time is the one the full list of contacts gives (cs_not_earliest).
 *
 * Built with CS_ESCALATE (single precision, where the device has double): a contact
 * is final only where a hit proved an exact zero (proof.h) no later than twice the
 * query's answer, and is not a limit's; every other query the refinement would report
 * goes to `escalated` instead, and the same search in double decides it (built with
 * CS_CONTACT_FLOAT, elementary_tests.cpp). Its float answer stands for nothing then, so
 * in earliest-only mode only a proven contact gives up other queries, by the end of
 * its proof's box, which bounds the query's answer in either precision. */
#include "conservative.h"
#include "coplanarity.h"
#include "cubic.h"
#include "pairs.h"
#include "proof.h"
#include "refine_earliest.h"
#include "refine_state.h"
#include "runtime/registration.h"
#include "runtime/worklist.h"

/* Budgets beyond the caller's work limit, after which a query answers as out of work:
 * rounds deeper than any box a precision can still halve in all three parameters for
 * a useful query, and boxes a query holds at once, which bounds the list's memory when
 * F vanishes (or stays within the separation) on a whole surface of parameters and
 * the boxes along it double each round. 4096 boxes: at 1024 and 2048, a few queries
 * of the real steps that the depth-first search used to settle as separate came out as
 * limits, one more false positive on cloth-funnel (double). */
#define CS_MOST_ROUNDS 1024u
#define CS_MOST_BOXES 4096u
/* From round 8 on, a box to refine is cut into eighths (three halvings at once,
 * cs_plan_cuts) rather than halved. By then the list holds only the queries whose boxes
 * close in on a contact or tile a curve of near-contacts, a round costs about one
 * visit's latency however few its boxes, and three halvings a round leave far fewer
 * rounds (H200, single precision: cloth-ball 39 rounds -> 23, 2.97 -> 2.85 ms; n-body
 * double 29 -> 16, 4.18 -> 4.06). Earlier rounds fill the device, and boxes cut finer
 * than the bounds ask would cost there. Nor is a query cut finer where its pieces could
 * take it past CS_MOST_BOXES, which would answer it as out of work (10 more such
 * answers on rod-twist in single precision). The round and the query's own boxes
 * decide, so answers still depend on the query alone. */
#define CS_CUT_FINER_FROM 8u
#define CS_FINER_HALVINGS 3

/* queries: (a, b, vertex_face, 0) as the screen emits them (narrow_phase_pairs.cl). */
#define CS_REFINE_PARAMS                                                                                         \
  __global const uint4 *queries, const uint n, __global const real *x0, __global const real *x1,               \
      __global const uint *faces, __global const uint *edges, const uint exact_input, const real tolerance,     \
      const real separation, const uint max_iterations, const uint use_filter CS_EARLIEST_PARAMS

/* A small box around the first touch that the cubic solver finds: along each parameter
 * F moves by half the tolerance from its centre, so a round or two of halving finds a
 * contact there, where the root box's halves would reach one only after many rounds;
 * from then on, every box that starts later is pruned. The box is searched like any
 * other, so answers keep their meaning. It is not smaller: centred on the closest
 * points of a near miss, a box whose first visit is a contact counts gaps within the
 * tolerance as contacts that the halving excludes (at an eighth, 171 false positives
 * on the real steps instead of 1, measured in double). Returns 0 where the cubic
 * solver finds no touch. */
inline int cs_guess_box(const real q[24], const cs_query* query, const int vertex_face, const real tolerance,
                        cs_box* b)
{
  real at[3];
  if (cs_cubic(q, vertex_face, tolerance, at) != CS_COLLIDES) return 0;
  const cs_trilinear f = cs_make_trilinear(query, vertex_face);
  const real tol = tolerance * cs_query_scale(query);
  /* How fast F moves along t, u and v there: the largest coordinate's slope. */
  real rate[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    real slope[3];
    cs_trilinear_slopes(&f, k, at, slope);
    for (int j = 0; j < 3; ++j) rate[j] = fmax(rate[j], fabs(slope[j]));
  }
  real lo[3], hi[3];
  for (int j = 0; j < 3; ++j) {
    /* The touch test allows the point a little outside the features. */
    const real centre = clamp(at[j], (real)0, (real)1);
    const real radius = rate[j] > 0 ? fmin((real)0.5, (real)0.5 * tol / rate[j]) : (real)0.5;
    lo[j] = fmax((real)0, centre - radius);
    hi[j] = fmin((real)1, centre + radius);
  }
  *b = cs_box_of(lo, hi);
  return 1;
}

/* The query's first boxes span the times at which its points may be coplanar (the
 * whole step with a minimum separation): their runs, of which it returns how many. A
 * query that is never coplanar gets none. use_filter: the screen ran in float, and the
 * non-penetration filter runs here in the refinement's precision (ccd_graph.cpp), on the
 * same coefficients. */
inline int cs_first_times(const cs_query* query, const uint vertex_face, const real separation, const uint use_filter,
                          real lo[CS_COPLANAR_RUNS], real hi[CS_COPLANAR_RUNS])
{
  lo[0] = 0;
  hi[0] = 1;
  if (separation != 0) return 1;
  cs_interval c[4];
  cs_coplanarity_cubic(query, (int)vertex_face, c);
  return use_filter && cs_cubic_keeps_sign(c) ? 0 : cs_coplanar_times(c, lo, hi);
}

__kernel void cs_refine_seed(CS_REFINE_PARAMS, __global cs_refine_state* state, __global cs_item* list,
                             __global uint* counts, const uint capacity)
{
  const uint i = get_global_id(0);
  cs_worklist_seed_begin(counts, n);
  if (i >= n) return;
  const uint4 pair = queries[i];
  cs_refine_state s;
  s.best[0] = s.best[1] = cs_key_of(2); /* no contact */
  s.work[0] = s.work[1] = s.work[2] = 0;
  s.flags = pair.z ? CS_FLAG_VERTEX_FACE : 0u;
#if CS_ESCALATE
  s.proven_end = CS_NO_TIME;
#endif
  cs_pair_vertices(pair.xy, pair.z, faces, edges, s.vertices);
  real q[24];
  cs_vertex_points(s.vertices, x0, x1, q);
  const cs_query query = cs_points_query(q, exact_input);
  real lo[CS_COPLANAR_RUNS], hi[CS_COPLANAR_RUNS];
  /* A query that is never coplanar gets one box after the step, which round 0 drops. */
  const int runs = cs_first_times(&query, pair.z, separation, use_filter, lo, hi);
  cs_item root;
  root.query = i;
  root.work = 0;
  root.box = cs_root_box();
  root.box.t0 = runs ? lo[0] : (real)2;
  root.box.t1 = runs ? hi[0] : (real)2;
  list[i] = root;
  for (int k = 1; k < runs; ++k) {
    cs_item more = root;
    more.box.t0 = lo[k];
    more.box.t1 = hi[k];
    const uint at = cs_worklist_seed_index(counts, n, capacity);
    if (at < capacity) list[at] = more;
  }
#if CS_EARLIEST_ACROSS
  if (earliest_only)
    cs_seed_earliest(cs_first_starts(state, n, i), runs ? cs_float_key_down(lo[0]) : CS_NO_TIME,
                     cs_query_objects(&s, vertex_object), found);
#endif
#if CS_KEEP_FUNCTION
  s.f = cs_points_trilinear(q, pair.z, exact_input);
  s.scale = cs_query_scale(&query);
#endif
  /* In single precision, and only for inputs rounded to float: their bounds stay wide
   * (within half an ulp of every coordinate), and the search would reach a contact only
   * after many rounds. Floats taken as the exact input narrow as fast without it, and
   * the guess is then a box more a query for little (H100, device ms: cloth-ball 2.56
   * -> 2.40 without it, n-body 3.53 -> 3.41). In double, where the search's answers are
   * within rounding of the exact time, a contact found early leaves the root box's
   * halves to be cut short by the tolerance before it: the median error of the times on
   * the real steps grew to the tolerance (armadillo-rollers 7e-11 -> 1e-5), for steps at
   * most 8% faster. Kept within the times the first boxes span. */
  if (!CS_REAL_DOUBLE && !exact_input && runs) {
    cs_item guess = root;
    if (cs_guess_box(q, &query, (int)pair.z, tolerance, &guess.box)) {
      guess.box.t0 = fmax(guess.box.t0, lo[0]);
      guess.box.t1 = fmin(guess.box.t1, hi[runs - 1]);
      if (guess.box.t0 < guess.box.t1) {
        const uint at = cs_worklist_seed_index(counts, n, capacity);
        if (at < capacity) list[at] = guess;
      }
    }
  }
  state[i] = s;
}

/* Round `round`'s visit of a box of a query whose state was `seen`, `work` boxes into
 * its search and `last_splits` of them halved last round: its function made (kept, or
 * again from the points), the work limits applied (past them the box answers
 * "collision" at its start, cs_visit_box), and the finer cuts of the late rounds.
 * *proven_end: with CS_ESCALATE, the end of the box a hit proved a zero in, else 2. */
inline int cs_round_visit(const cs_refine_state* seen, const cs_box box, const uint round, const uint work,
                          const uint last_splits, __global const real* x0, __global const real* x1,
                          const uint exact_input, const real tolerance, const real separation,
                          const uint max_iterations, const real before, int* slack, int* limited, real* t,
                          cs_box* lo, cs_box* hi, cs_cuts* cuts, real* proven_end)
{
  const int vertex_face = (seen->flags & CS_FLAG_VERTEX_FACE) != 0;
#if CS_KEEP_FUNCTION
  const cs_trilinear f = seen->f;
  const real scale = seen->scale;
#else
  real points[24];
  cs_vertex_points(seen->vertices, x0, x1, points);
  const cs_trilinear f = cs_points_trilinear(points, (uint)vertex_face, exact_input);
  const real scale = cs_points_scale(points, exact_input);
#endif
  const int out_of_work = work >= max_iterations || round >= CS_MOST_ROUNDS || last_splits > CS_MOST_BOXES / 2;
  const int levels =
      round >= CS_CUT_FINER_FROM && last_splits << CS_FINER_HALVINGS <= CS_MOST_BOXES / 2 ? CS_FINER_HALVINGS : 1;
  const int visit = cs_visit_box(&f, box, vertex_face, tolerance * scale, tolerance, separation, before,
                                 out_of_work, levels, slack, limited, t, lo, hi, cuts);
  *proven_end = 2;
#if CS_ESCALATE
  if (visit == CS_BOX_HIT && !*limited) {
    const cs_box sought = cs_proof_box(box, vertex_face);
    if (cs_zero_proven(&f, sought, vertex_face)) *proven_end = sought.t1;
  }
#endif
  return visit;
}

/* The boxes a visit leaves into the next round's list: its two halves, the narrowed box,
 * or the pieces of a cut. */
inline void cs_round_store(__local uint* group, __global uint* counts, const uint round, const uint capacity,
                           const int visit, const cs_item lo, const cs_item hi, const cs_cuts cuts,
                           __global cs_item* out)
{
  const uint boxes = visit == CS_BOX_SPLIT ? 2u : visit == CS_BOX_NARROW ? 1u : visit == CS_BOX_CUT ? cs_pieces(cuts) : 0u;
  const uint at = cs_worklist_append(group, counts, round, boxes);
  if (visit == CS_BOX_CUT) {
    for (uint j = 0; j < boxes; ++j)
      if (cs_worklist_fits(counts, capacity, at + j)) {
        cs_item piece = lo;
        piece.box = cs_piece(lo.box, cuts, j);
        out[at + j] = piece;
      }
  } else {
    if (boxes > 0 && cs_worklist_fits(counts, capacity, at)) out[at] = lo;
    if (boxes > 1 && cs_worklist_fits(counts, capacity, at + 1)) out[at + 1] = hi;
  }
}

__kernel void cs_refine_round(CS_REFINE_PARAMS, __global cs_refine_state* state, __global const cs_item* in,
                              __global cs_item* out, __global uint* counts, const uint round, const uint capacity)
{
  __local uint group[2];
  const uint items = cs_worklist_items(counts, round, capacity);
  /* Everything else a round writes to the state is a minimum, an or or a store of what
   * the replay stores again. */
  const int replay = cs_worklist_replay(counts, round);
  const uint now = round % 2;
  for (uint base = get_group_id(0) * get_local_size(0); base < items; base += get_global_size(0)) {
    const uint i = base + get_local_id(0);
    int visit = CS_BOX_DROP;
    cs_item lo, hi;
    cs_cuts cuts = 0;
    if (i < items) {
      const cs_item it = in[i];
      __global cs_refine_state* s = state + it.query;
      const cs_refine_state seen = *s;
      const real before = cs_time_of(seen.best[1 - now]);
      const uint last_splits = seen.work[(round + 2) % 3]; /* this round's boxes, halved */
      const uint work = it.work + last_splits;
      int slack = 0, limited = 0;
      real t = before, proven_end = 2;
#if CS_EARLIEST_ACROSS
      __global uint* first = cs_first_starts(state, n, it.query);
      const int given_up = earliest_only && cs_not_earliest(&seen, first, round, before, tolerance, vertex_object, found);
      if (given_up && !(seen.flags & CS_FLAG_NOT_EARLIEST)) atomic_or(&s->flags, CS_FLAG_NOT_EARLIEST);
#else
      const int given_up = 0;
#endif
      /* Not a box after the step: the seed's of a query that is never coplanar. */
      if (!given_up && it.box.t0 <= 1)
        visit = cs_round_visit(&seen, it.box, round, work, last_splits, x0, x1, exact_input, tolerance, separation,
                               max_iterations, before, &slack, &limited, &t, &lo.box, &hi.box, &cuts, &proven_end);
      cs_key_lower(&s->best[now], seen.best[now], cs_key_of(visit == CS_BOX_HIT ? fmin(before, t) : before));
      /* After the visit: issued before it, this store to a word that every box of the
       * query writes made cloth-ball's refinement a third slower in single precision. */
      s->work[(round + 1) % 3] = 0;
      if (slack || limited) atomic_or(&s->flags, (slack ? CS_FLAG_SLACK : 0u) | (limited ? CS_FLAG_LIMIT : 0u));
#if CS_ESCALATE
      if (proven_end <= 1) {
        const uint end = cs_float_key_up(proven_end);
        if (end < seen.proven_end) atomic_min(&s->proven_end, end);
      }
#endif
      if (visit >= CS_BOX_SPLIT) {
        if (!replay) atomic_add(&s->work[round % 3], visit == CS_BOX_CUT ? cs_pieces(cuts) / 2 : 1u);
        lo.query = hi.query = it.query;
        lo.work = hi.work = work;
      }
#if CS_EARLIEST_ACROSS
      if (earliest_only)
        cs_round_earliest(first, round, visit, lo.box.t0, t, proven_end, &seen, vertex_object, found);
#endif
    }
    cs_round_store(group, counts, round, capacity, visit, lo, hi, cuts, out);
  }
  cs_worklist_check_loops(counts, round);
}

#if CS_ESCALATE
#define CS_ESCALATED_PARAMS , CS_EMITTER_PARAMS(uint4, escalated)
/* A contact stands where a hit proved a zero no later than twice its time (so its time
 * is at least half the exact one) and no limit cut the search short. */
inline int cs_contact_stands(const cs_refine_state* s, const uint status, const real t)
{
  return status == CS_COLLIDES && s->proven_end != CS_NO_TIME && t >= (real)0.5 * (real)as_float(s->proven_end);
}
#else
#define CS_ESCALATED_PARAMS
#endif

/* Each query's answer, once no box of it is left, into the contacts of its kind (with
 * CS_ESCALATE, the queries it does not settle into `escalated`, as they came). */
__kernel void cs_refine_finish(CS_REFINE_PARAMS, __global const cs_refine_state* state,
                               CS_EMITTER_PARAMS(uint4, vf_contacts),
                               CS_EMITTER_PARAMS(uint4, ee_contacts) CS_ESCALATED_PARAMS)
{
  CS_EMITTER_BEGIN(vf_contacts);
  CS_EMITTER_BEGIN(ee_contacts);
#if CS_ESCALATE
  CS_EMITTER_BEGIN(escalated);
#endif
  const uint i = get_global_id(0);
  if (i < n) {
    const cs_refine_state s = state[i];
    const real best = fmin(cs_time_of(s.best[0]), cs_time_of(s.best[1]));
    const uint status = (s.flags & CS_FLAG_LIMIT) ? CS_LIMIT : best <= 1 ? CS_COLLIDES : CS_SEPARATE;
    if (status != CS_SEPARATE && !(s.flags & CS_FLAG_NOT_EARLIEST)) {
      const uint4 q = queries[i];
      const real t = cs_final_time(best, s.flags & CS_FLAG_SLACK, tolerance);
#if CS_ESCALATE
      if (!cs_contact_stands(&s, status, t)) {
        CS_EMIT(escalated, q);
      } else
#endif
      {
        const uint4 contact = cs_contact(q.xy, t, status);
        if (q.z) CS_EMIT(vf_contacts, contact);
        else CS_EMIT(ee_contacts, contact);
      }
    }
  }
  CS_EMITTER_END(vf_contacts);
  CS_EMITTER_END(ee_contacts);
#if CS_ESCALATE
  CS_EMITTER_END(escalated);
#endif
}
