#ifndef CSTREAMS_CCD_QUERY_H
#define CSTREAMS_CCD_QUERY_H
/* One elementary query: eight points, x[0..3] at t = 0 and x[4..7] at t = 1, in the
 * order vertex, face (vertex-face) or edge a, edge b (edge-edge). Each coordinate is
 * held as an interval that contains the exact input: queries given in double and
 * solved in float are rounded to nearest on the host, so the exact value lies within
 * half an ulp of the float, and the interval is one step out on each side. */
#include "real.h"

typedef struct {
  cs_interval x[8][3];
} cs_query;

inline cs_query cs_load_query(__global const real* q, const size_t index, const int exact)
{
  cs_query out;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) {
      const real v = q[index * 24 + i * 3 + k];
      out.x[i][k] = exact ? cs_iv(v, v) : cs_iv(cs_down(v), cs_up(v));
    }
  return out;
}

/* Statuses written per query. */
#define CS_SEPARATE 0u   /* proven not to collide */
#define CS_COLLIDES 1u   /* a contact within the tolerance */
#define CS_FILTERED 2u   /* culled by the non-penetration filter: cannot collide */
#define CS_LIMIT 3u      /* the solver ran out of iterations or stack: reported as colliding */

#endif
