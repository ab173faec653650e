#ifndef CSTREAMS_CCD_PAIRS_H
#define CSTREAMS_CCD_PAIRS_H
/* Candidate pairs of the device pipeline as queries, and contacts as they are emitted.
 * vertex_face: a pair is (vertex, face), else (edge, edge); positions x0, x1 hold three
 * reals a vertex. */
#include "query.h"
#include "trilinear.h"

/* The pair's four vertices: the vertex and the face's three, or both edges' two. */
inline void cs_pair_vertices(const uint2 p, const uint vertex_face, __global const uint* faces,
                             __global const uint* edges, uint v[4])
{
  if (vertex_face) {
    v[0] = p.x;
    v[1] = faces[3 * p.y];
    v[2] = faces[3 * p.y + 1];
    v[3] = faces[3 * p.y + 2];
  } else {
    v[0] = edges[2 * p.x];
    v[1] = edges[2 * p.x + 1];
    v[2] = edges[2 * p.y];
    v[3] = edges[2 * p.y + 1];
  }
}

/* Four vertices' positions at both ends of the step: x0's then x1's. */
inline void cs_vertex_points(const uint v[4], __global const real* x0, __global const real* x1, real out[24])
{
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      out[3 * i + k] = x0[3 * v[i] + k];
      out[12 + 3 * i + k] = x1[3 * v[i] + k];
    }
}

inline void cs_pair_points(const uint2 p, const uint vertex_face, __global const real* x0, __global const real* x1,
                           __global const uint* faces, __global const uint* edges, real out[24])
{
  uint v[4];
  cs_pair_vertices(p, vertex_face, faces, edges, v);
  cs_vertex_points(v, x0, x1, out);
}

/* Exact inputs are the data itself; float inputs were rounded to nearest from the
 * caller's values, so each stands for a one-ulp interval. */
inline cs_query cs_points_query(const real q[24], const uint exact_input)
{
  cs_query out;
  for (int j = 0; j < 8; ++j)
    for (int k = 0; k < 3; ++k) {
      const real v = q[3 * j + k];
      out.x[j][k] = exact_input ? cs_iv(v, v) : cs_iv(cs_down(v), cs_up(v));
    }
  return out;
}

inline cs_query cs_pair_query(const uint2 p, const uint vertex_face, __global const real* x0,
                              __global const real* x1, __global const uint* faces, __global const uint* edges,
                              const uint exact_input)
{
  real q[24];
  cs_pair_points(p, vertex_face, x0, x1, faces, edges, q);
  return cs_points_query(q, exact_input);
}

/* The contact function of the points q (cs_pair_points), through intervals only where
 * they stand for inputs rounded to float. Exact points, floats given as floats and any
 * input in double, skip the interval arithmetic (H100: the conservative screen of
 * cloth-ball 0.31 -> 0.26 ms and of n-body 0.72 -> 0.58, n-body's refinement in double
 * 1.17 -> 1.03; pocl: cloth-ball's screen about a quarter faster). */
inline cs_trilinear cs_points_trilinear(const real q[24], const uint vertex_face, const uint exact_input)
{
  if (exact_input) return cs_make_exact_trilinear(q, (int)vertex_face);
  const cs_query query = cs_points_query(q, 0);
  return cs_make_trilinear(&query, (int)vertex_face);
}

/* The largest magnitude among the points q, at least CS_TINY: cs_query_scale of
 * cs_points_query(q, exact_input), where an input rounded to float reaches one step
 * above its own. */
inline real cs_points_scale(const real q[24], const uint exact_input)
{
  real s = 0;
  for (int i = 0; i < 24; ++i) s = fmax(s, fabs(q[i]));
  return exact_input ? fmax(s, CS_TINY) : cs_up(s);
}

/* A contact: (feature a, feature b, time bits), the time as the bits of a double (low
 * word first) or of a float and a zero word; in float, rounded down, where the solver
 * ran in double for a float caller (CS_CONTACT_FLOAT: refine.cl's escalation). Built
 * with CS_MARK_LIMIT, a contact that only a solver limit reported carries its time
 * negated (the sign bit: times are never negative, and -0 keeps it), so a caller that
 * counts limits can tell. */
inline uint4 cs_contact(const uint2 p, const real t, const uint status)
{
#if CS_MARK_LIMIT
  const real sign = status == CS_LIMIT ? (real)-1 : (real)1;
#else
  const real sign = 1;
  (void)status;
#endif
#if CS_REAL_DOUBLE && !CS_CONTACT_FLOAT
  return (uint4)(p.x, p.y, as_uint2(sign * t));
#else
  return (uint4)(p.x, p.y, as_uint((float)sign * cs_float_down(t)), 0u);
#endif
}

#endif
