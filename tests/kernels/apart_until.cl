/* The cubic test and the time before which it cannot find a contact, side by side, for
 * test_narrow_phase: query i is 24 reals (four points at t = 0, then at t = 1); times[i]
 * is the cubic's time of impact (2 where it finds none) and until[i] what
 * cs_apart_until gives with cs_touching_margin. Built with CS_REAL_DOUBLE. */
#include "ccd/cubic.h"
#include "ccd/pairs.h"

__kernel void test_apart_until(__global const real* queries, const uint n, const uint vertex_face,
                               const real tolerance, __global real* times, __global real* until)
{
  const uint i = get_global_id(0);
  if (i >= n) return;
  real q[24], at[3];
  for (int k = 0; k < 24; ++k) q[k] = queries[24 * i + k];
  times[i] = cs_cubic(q, (int)vertex_face, tolerance, at) == CS_COLLIDES ? at[0] : 2;
  const real scale = cs_points_scale(q, 1);
  until[i] = cs_apart_until(q, (int)vertex_face, cs_touching_margin(tolerance * scale, scale));
}
