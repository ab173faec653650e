/* Elementary CCD tests over a batch of queries, one work-item each. Built with
 * CS_REAL_DOUBLE (precision) and CS_SOLVER (CS_SOLVER_CUBIC or CS_SOLVER_CONSERVATIVE).
 * queries: 24 reals per query (see query.h); status: CS_SEPARATE, CS_COLLIDES,
 * CS_FILTERED or CS_LIMIT; toi: the time of impact (1 when separate). */
#include "conservative.h"
#include "cubic.h"
#include "filter.h"

#define CS_SOLVER_CUBIC 0
#define CS_SOLVER_CONSERVATIVE 1

__kernel void cs_narrow_phase(__global const real* queries, const uint n, const uint vertex_face,
                              const uint exact_input, const real tolerance, const real separation,
                              const uint max_iterations, const uint use_filter, __global uint* status,
                              __global real* toi)
{
  const size_t i = get_global_id(0);
  if (i >= n) return;
  real t = 1;
  uint s;
  const cs_query q = cs_load_query(queries, i, exact_input);
  if (use_filter && separation == 0 && cs_non_penetration_filter(&q, vertex_face)) {
    s = CS_FILTERED;
  } else {
#if CS_SOLVER == CS_SOLVER_CUBIC
    (void)max_iterations;
    real plain[24];
    for (int j = 0; j < 24; ++j) plain[j] = queries[i * 24 + j];
    s = cs_cubic(plain, vertex_face, tolerance, &t);
#else
    s = cs_conservative(&q, vertex_face, tolerance, separation, max_iterations, &t);
#endif
  }
  status[i] = s;
  toi[i] = t;
}
