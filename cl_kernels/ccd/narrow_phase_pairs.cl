/* The first step of the elementary tests over candidate pairs, one work-item a pair.
 * Built with CS_REAL_DOUBLE (precision) and, by the scheduler, CS_REGISTRATION. The
 * deforming non-penetration filter runs first (use_filter, and no minimum separation). */
#include "conservative.h"
#include "cubic.h"
#include "filter.h"
#include "pairs.h"
#include "streams.h"
#include "runtime/registration.h"

inline int cs_filtered(const cs_query* q, const uint vertex_face, const uint use_filter, const real separation)
{
  return use_filter && separation == 0 && cs_non_penetration_filter(q, (int)vertex_face);
}

CS_DEFINE_STREAM_ITEM(uint2)

/* The cubic solver, to the end: colliding pairs are emitted as contacts of their kind. */
__kernel void cs_cubic_pairs(CS_FOUR_STREAMS(uint2), __global const real* x0, __global const real* x1,
                             __global const uint* faces, __global const uint* edges, const uint exact_input,
                             const real tolerance, const real separation, const uint use_filter,
                             CS_EMITTER_PARAMS(uint4, vf_contacts), CS_EMITTER_PARAMS(uint4, ee_contacts))
{
  CS_EMITTER_BEGIN(vf_contacts);
  CS_EMITTER_BEGIN(ee_contacts);
  uint2 pair;
  uint vertex_face;
  if (cs_stream_item_uint2(get_global_id(0), CS_FOUR_STREAM_ARGS, &pair, &vertex_face)) {
    real q[24];
    cs_pair_points(pair, vertex_face, x0, x1, faces, edges, q);
    const cs_query query = cs_points_query(q, exact_input);
    if (!cs_filtered(&query, vertex_face, use_filter, separation)) {
      real at[3];
      const uint s = cs_cubic(q, (int)vertex_face, tolerance, at);
      if (s == CS_COLLIDES && vertex_face) CS_EMIT(vf_contacts, cs_contact(pair, at[0], s));
      if (s == CS_COLLIDES && !vertex_face) CS_EMIT(ee_contacts, cs_contact(pair, at[0], s));
    }
  }
  CS_EMITTER_END(vf_contacts);
  CS_EMITTER_END(ee_contacts);
}

/* Whether the bounds over the whole parameter box and the filter leave a pair open.
 * The bounds go first: they settle most pairs, the filter is as costly and only runs
 * on what they leave. Either way the pair is open only where neither settles it. */
inline int cs_screen_open(const uint2 pair, const uint vertex_face, __global const real* x0, __global const real* x1,
                          __global const uint* faces, __global const uint* edges, const uint exact_input,
                          const real separation, const uint use_filter)
{
  {
    const cs_query query = cs_pair_query(pair, vertex_face, x0, x1, faces, edges, exact_input);
    const cs_trilinear f = cs_make_trilinear(&query, (int)vertex_face);
    real width, farthest, nearest[2], first, spread[3];
    if (!cs_trilinear_root_bounds(&f, separation, &width, &farthest, nearest, &first, spread)) return 0;
  }
  if (!use_filter || separation != 0) return 1;
  /* Loaded again rather than kept: the bounds need every register they can get. */
  const cs_query query = cs_pair_query(pair, vertex_face, x0, x1, faces, edges, exact_input);
  return !cs_filtered(&query, vertex_face, use_filter, separation);
}

/* The conservative solver's screen over every candidate stream: the filter and the
 * bounds over the whole parameter box settle most pairs at once; the rest are emitted
 * as (a, b, vertex_face, 0) for refinement (refine.cl), one list for all kinds so that
 * its rounds are paid once. */
__kernel void cs_screen_pairs(CS_FOUR_STREAMS(uint2), __global const real* x0, __global const real* x1,
                              __global const uint* faces, __global const uint* edges, const uint exact_input,
                              const real separation, const uint use_filter, CS_EMITTER_PARAMS(uint4, unresolved))
{
  CS_EMITTER_BEGIN(unresolved);
  uint2 pair;
  uint vertex_face;
  if (cs_stream_item_uint2(get_global_id(0), CS_FOUR_STREAM_ARGS, &pair, &vertex_face) &&
      cs_screen_open(pair, vertex_face, x0, x1, faces, edges, exact_input, separation, use_filter))
    CS_EMIT(unresolved, (uint4)(pair, vertex_face, 0u));
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
