/* The first step of the elementary tests over candidate pairs, one work-item a pair.
 * Built with CS_REAL_DOUBLE (precision) and, by the scheduler, CS_REGISTRATION. The
 * deforming non-penetration filter (use_filter, and no minimum separation) settles the
 * pairs it proves apart, whichever test it goes with. */
#include "conservative.h"
#include "cubic.h"
#include "earliest.h"
#include "filter.h"
#include "pairs.h"
#include "streams.h"
#include "runtime/registration.h"

inline int cs_filtered(const cs_query* q, const uint vertex_face, const uint use_filter, const real separation)
{
  return use_filter && separation == 0 && cs_non_penetration_filter(q, (int)vertex_face);
}

CS_DEFINE_STREAM_ITEM(uint2)

/* The later of pair p's objects' earliest times so far: a contact of the pair at that
 * time or later lowers neither. */
inline float cs_pair_known(const uint2 p, const uint vertex_face, __global const uint* faces,
                           __global const uint* edges, __global const uint* vertex_object,
                           __global const uint* earliest_times)
{
  uint objects[2];
  cs_pair_objects(p, vertex_face, faces, edges, vertex_object, objects);
  return as_float(max(earliest_times[objects[0]], earliest_times[objects[1]]));
}

/* Whether item i of the candidate streams is left for the cubic, and until when its
 * features' boxes stay apart (cs_apart_until), before which the cubic finds no contact.
 * It is left where they do not stay apart through the step, and, where `earliest` is
 * set (a constant, so that the test without it compiles as if this were not there),
 * only where they meet before both its objects' earliest times so far: a contact no
 * earlier cannot lower either. An object whose time is 0 already is done with before
 * the points are read. The kind is a constant in each call of cs_apart_until: indexed
 * by a kind known only at run time, the points went to a 208-byte stack frame on
 * NVIDIA. */
inline int cs_cubic_open(const uint i, CS_FOUR_STREAMS(uint2), __global const real* x0, __global const real* x1,
                         __global const uint* faces, __global const uint* edges, const real tolerance,
                         const int earliest, __global const uint* vertex_object, __global const uint* earliest_times,
                         real* until)
{
  uint2 pair;
  uint vertex_face;
  if (!cs_stream_item_uint2(i, CS_FOUR_STREAM_ARGS, &pair, &vertex_face)) return 0;
  float known = 1;
  if (earliest) {
    known = cs_pair_known(pair, vertex_face, faces, edges, vertex_object, earliest_times);
    if (known == 0) return 0;
  }
  real q[24];
  cs_pair_points(pair, vertex_face, x0, x1, faces, edges, q);
  const real scale = cs_points_scale(q, 1);
  const real margin = cs_touching_margin(tolerance * scale, scale);
  *until = vertex_face ? cs_apart_until(q, 1, margin) : cs_apart_until(q, 0, margin);
  return earliest ? *until < known : *until <= 1;
}

/* The cubic test of item i of the candidate streams, a pair cs_cubic_open left with its
 * bound `until`: whether it is a contact to emit, and its pair, kind and time. Where
 * `earliest` is set, the pair is given up if its objects' earliest times have come down
 * to its bound since. */
inline int cs_cubic_contact(const uint i, CS_FOUR_STREAMS(uint2), __global const real* x0, __global const real* x1,
                            __global const uint* faces, __global const uint* edges, const uint exact_input,
                            const real tolerance, const real separation, const uint use_filter, const int earliest,
                            const real until, __global const uint* vertex_object,
                            __global const uint* earliest_times, uint2* pair, uint* vertex_face, real* t)
{
  cs_stream_item_uint2(i, CS_FOUR_STREAM_ARGS, pair, vertex_face);
  if (earliest && until >= cs_pair_known(*pair, *vertex_face, faces, edges, vertex_object, earliest_times)) return 0;
  real q[24], at[3];
  cs_pair_points(*pair, *vertex_face, x0, x1, faces, edges, q);
  const uint found = *vertex_face ? cs_cubic(q, 1, tolerance, at) : cs_cubic(q, 0, tolerance, at);
  if (found != CS_COLLIDES) return 0;
  const cs_query query = cs_points_query(q, exact_input);
  *t = at[0];
  return !cs_filtered(&query, *vertex_face, use_filter, separation);
}

/* The cubic solver, to the end: colliding pairs are emitted as contacts of their kind.
 * A pair is a contact where the cubic finds one and the filter does not prove the pair
 * apart, so the filter runs only on the cubic's few contacts: in interval arithmetic
 * it costs more than the cubic saves where it runs first on every pair (H100,
 * cloth-ball's tests 0.46 -> 0.40 ms, n-body's 0.83 -> 0.55). Gathering a group's
 * contacts before filtering them, as the screen does, measured slower here (n-body
 * 0.58 ms): few pairs collide. What the filter still costs is registers: 78 a
 * work-item, 63 without it, which took 0.28 ms on cloth-ball.
 *
 * In a scene of objects (CS_EARLIEST_ACROSS) the kernel takes each vertex's object and
 * a word per object, which only cs_cubic_earliest_pairs uses. */
#if CS_EARLIEST_ACROSS
#define CS_OBJECT_PARAMS , __global const uint *vertex_object, __global uint *earliest
#define CS_OBJECT_ARGS vertex_object, earliest
#else
#define CS_OBJECT_PARAMS
#define CS_OBJECT_ARGS 0, 0
#endif
#define CS_CUBIC_PARAMS                                                                                      \
  CS_FOUR_STREAMS(uint2), __global const real *x0, __global const real *x1, __global const uint *faces,      \
      __global const uint *edges, const uint exact_input, const real tolerance, const real separation,       \
      const uint use_filter CS_OBJECT_PARAMS

/* Lowers the earliest times of pair p's objects to t. */
inline void cs_lower_objects(const uint2 p, const uint vertex_face, __global const uint* faces,
                             __global const uint* edges, const real t, __global const uint* vertex_object,
                             __global uint* earliest)
{
  uint objects[2];
  cs_pair_objects(p, vertex_face, faces, edges, vertex_object, objects);
  cs_lower_earliest(earliest, objects[0], cs_time_key(t));
  cs_lower_earliest(earliest, objects[1], cs_time_key(t));
}

/* CS_CUBIC_ITEM(mode) sets `has`, whether this work-item runs the cubic, on `item` with
 * its bound `until`. On a GPU a group gathers the items cs_cubic_open leaves in local
 * memory and tests them side by side: tested where they lay, nearly every warp held one
 * and ran the cubic (from swept boxes, the bound left about half of cloth-ball's
 * candidates, and a sixth where earliest times alone are asked for). With the kinds as
 * constants, H200: cloth-ball's tests 0.397 -> 0.390 ms, earliest-only 0.357 -> 0.272;
 * n-body's 0.554 -> 0.513, earliest-only 0.493 -> 0.400. Either change alone was slower
 * somewhere: the constants alone took 85 registers and cloth-ball's tests 0.47 ms. A
 * CPU runs a group's work-items one after another, so no cubic holds others up: there
 * the items stay where they are and only earliest times take the bound (pocl:
 * cloth-ball's tests took a quarter longer gathered). */
#if CS_CPU
#define CS_CUBIC_ITEM(mode)                                                                                 \
  const uint item = (uint)get_global_id(0);                                                                 \
  real until = 0;                                                                                           \
  const int has = mode ? cs_cubic_open(item, CS_FOUR_STREAM_ARGS, x0, x1, faces, edges, tolerance, mode,    \
                                       CS_OBJECT_ARGS, &until)                                              \
                       : item < n0 + n1 + n2 + n3
#else
#define CS_CUBIC_ITEM(mode)                                                                                 \
  __local uint open[CS_WG_SIZE], open_count;                                                                \
  __local real open_until[CS_WG_SIZE];                                                                      \
  if (get_local_id(0) == 0) open_count = 0;                                                                 \
  barrier(CLK_LOCAL_MEM_FENCE);                                                                             \
  {                                                                                                         \
    real bound;                                                                                             \
    if (cs_cubic_open((uint)get_global_id(0), CS_FOUR_STREAM_ARGS, x0, x1, faces, edges, tolerance, mode,   \
                      CS_OBJECT_ARGS, &bound)) {                                                            \
      const uint k = atomic_inc(&open_count);                                                               \
      open[k] = (uint)get_global_id(0);                                                                     \
      open_until[k] = bound;                                                                                \
    }                                                                                                       \
  }                                                                                                         \
  barrier(CLK_LOCAL_MEM_FENCE);                                                                             \
  const int has = get_local_id(0) < open_count;                                                             \
  const uint item = has ? open[get_local_id(0)] : 0u;                                                       \
  const real until = has ? open_until[get_local_id(0)] : 0
#endif

/* Both kernels' body; `mode` is the constant 0 or 1 that cs_cubic_open takes as
 * `earliest` (a name of its own: CS_OBJECT_ARGS names the kernel's `earliest`). */
#define CS_CUBIC_PAIRS_BODY(mode)                                                                           \
  CS_EMITTER_BEGIN(vf_contacts);                                                                            \
  CS_EMITTER_BEGIN(ee_contacts);                                                                            \
  CS_CUBIC_ITEM(mode);                                                                                      \
  uint2 pair;                                                                                               \
  uint vertex_face;                                                                                         \
  real t;                                                                                                   \
  if (has && cs_cubic_contact(item, CS_FOUR_STREAM_ARGS, x0, x1, faces, edges, exact_input, tolerance,      \
                              separation, use_filter, mode, until, CS_OBJECT_ARGS, &pair, &vertex_face, &t)) { \
    if (vertex_face) CS_EMIT(vf_contacts, cs_contact(pair, t, CS_COLLIDES));                                \
    else CS_EMIT(ee_contacts, cs_contact(pair, t, CS_COLLIDES));                                            \
    if (mode) cs_lower_objects(pair, vertex_face, faces, edges, t, CS_OBJECT_ARGS);                         \
  }                                                                                                         \
  CS_EMITTER_END(vf_contacts);                                                                              \
  CS_EMITTER_END(ee_contacts)

CS_GROUP_KERNEL void cs_cubic_pairs(CS_CUBIC_PARAMS, CS_EMITTER_PARAMS(uint4, vf_contacts),
                                    CS_EMITTER_PARAMS(uint4, ee_contacts))
{
  CS_CUBIC_PAIRS_BODY(0);
}

#if CS_EARLIEST_ACROSS
/* cs_cubic_pairs in a step that reports each object's earliest time alone: the pairs
 * that cannot lower one skip the cubic, and the contacts found lower their objects'
 * times at once, so that the pairs after them skip more. The earliest times stay the
 * full list's. */
CS_GROUP_KERNEL void cs_cubic_earliest_pairs(CS_CUBIC_PARAMS, CS_EMITTER_PARAMS(uint4, vf_contacts),
                                             CS_EMITTER_PARAMS(uint4, ee_contacts))
{
  CS_CUBIC_PAIRS_BODY(1);
}
#endif

/* Whether the bounds over the whole parameter box leave a pair open. */
inline int cs_bounds_leave_open(const uint2 pair, const uint vertex_face, __global const real* x0,
                                __global const real* x1, __global const uint* faces, __global const uint* edges,
                                const uint exact_input, const real separation)
{
  real q[24];
  cs_pair_points(pair, vertex_face, x0, x1, faces, edges, q);
  const cs_trilinear f = cs_points_trilinear(q, vertex_face, exact_input);
  real width, farthest, nearest[2], first, spread[3];
  return cs_trilinear_root_bounds(&f, separation, &width, &farthest, nearest, &first, spread);
}

/* The conservative solver's screen over every candidate stream: the bounds over the
 * whole parameter box and the filter settle most pairs at once; the rest are emitted
 * as (a, b, vertex_face, 0) for refinement (refine.cl), one list for all kinds so that
 * its rounds are paid once. The bounds go first: they settle most pairs, and the
 * filter, as costly, runs on what they leave. A warp would run the filter wherever
 * one of its pairs is left, so the group's pairs left open are gathered in local
 * memory and filtered side by side (H100: cloth-ball's screen 0.37 -> 0.31 ms, n-body's
 * 0.78 -> 0.72; on pocl the same within its noise). */
CS_GROUP_KERNEL void cs_screen_pairs(CS_FOUR_STREAMS(uint2), __global const real* x0, __global const real* x1,
                                     __global const uint* faces, __global const uint* edges, const uint exact_input,
                                     const real separation, const uint use_filter,
                                     CS_EMITTER_PARAMS(uint4, unresolved))
{
  __local uint open[CS_WG_SIZE], count;
  CS_EMITTER_BEGIN(unresolved);
  if (get_local_id(0) == 0) count = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  uint2 pair;
  uint vertex_face;
  if (cs_stream_item_uint2(get_global_id(0), CS_FOUR_STREAM_ARGS, &pair, &vertex_face) &&
      cs_bounds_leave_open(pair, vertex_face, x0, x1, faces, edges, exact_input, separation))
    open[atomic_inc(&count)] = (uint)get_global_id(0);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) < count) {
    cs_stream_item_uint2(open[get_local_id(0)], CS_FOUR_STREAM_ARGS, &pair, &vertex_face);
    const cs_query query = cs_pair_query(pair, vertex_face, x0, x1, faces, edges, exact_input);
    if (!cs_filtered(&query, vertex_face, use_filter, separation)) CS_EMIT(unresolved, (uint4)(pair, vertex_face, 0u));
  }
  CS_EMITTER_END(unresolved);
}

/* Which pairs the filter alone settles, for reports of how the tests decide (the
 * kernels above apply the filter themselves). */
__kernel void cs_filter_flags(__global const uint2* pairs, const uint n, const uint vertex_face,
                              __global const real* x0, __global const real* x1, __global const uint* faces,
                              __global const uint* edges, const uint exact_input, const real separation,
                              const uint use_filter, __global uint* culled)
{
  const uint i = get_global_id(0);
  if (i >= n) return;
  const cs_query query = cs_pair_query(pairs[i], vertex_face, x0, x1, faces, edges, exact_input);
  culled[i] = (uint)cs_filtered(&query, vertex_face, use_filter, separation);
}
