/* Elementary tests over the candidate pairs of the device pipeline. Built, like
 * narrow_phase.cl, with CS_REAL_DOUBLE and CS_SOLVER, and with CS_REGISTRATION by the
 * scheduler. */
#include "conservative.h"
#include "cubic.h"
#include "filter.h"
#include "runtime/registration.h"

#define CS_SOLVER_CUBIC 0
#define CS_SOLVER_CONSERVATIVE 1

/* The same tests over candidate pairs whose positions are on the device:
 * vertex_face selects (vertex, face) pairs, else (edge, edge) pairs. Colliding pairs
 * are emitted as (feature a, feature b, time of impact): the time as the bits of a
 * double (low word first), or of a float and a zero word in single precision. */
#if CS_REAL_DOUBLE
inline uint2 cs_time_bits(const double t) { return as_uint2(t); }
#else
inline uint2 cs_time_bits(const float t) { return (uint2)(as_uint(t), 0u); }
#endif

inline void cs_gather(__global const real* x0, __global const real* x1, const uint* v, real out[24])
{
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      out[3 * i + k] = x0[3 * v[i] + k];
      out[12 + 3 * i + k] = x1[3 * v[i] + k];
    }
}

__kernel void cs_narrow_phase_pairs(__global const uint2* pairs, const uint n, const uint vertex_face,
                                    __global const real* x0, __global const real* x1, __global const uint* faces,
                                    __global const uint* edges, const uint exact_input, const real tolerance,
                                    const real separation, const uint max_iterations, const uint use_filter,
                                    CS_EMITTER_PARAMS(uint4, contacts))
{
  CS_EMITTER_BEGIN(contacts);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 p = pairs[i];
    uint v[4];
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
    real q[24];
    cs_gather(x0, x1, v, q);
    cs_query query;
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 3; ++k)
        query.x[j][k] = exact_input ? cs_iv(q[3 * j + k], q[3 * j + k]) : cs_iv(cs_down(q[3 * j + k]), cs_up(q[3 * j + k]));
    real t = 1;
    uint s = CS_FILTERED;
    if (!(use_filter && separation == 0 && cs_non_penetration_filter(&query, vertex_face))) {
#if CS_SOLVER == CS_SOLVER_CUBIC
      (void)max_iterations;
      s = cs_cubic(q, (int)vertex_face, tolerance, &t);
#else
      s = cs_conservative(&query, (int)vertex_face, tolerance, separation, max_iterations, &t);
#endif
    }
    if (s == CS_COLLIDES || s == CS_LIMIT) CS_EMIT(contacts, (uint4)(p.x, p.y, cs_time_bits(t)));
  }
  CS_EMITTER_END(contacts);
}
