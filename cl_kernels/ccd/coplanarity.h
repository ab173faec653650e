#ifndef CSTREAMS_CCD_COPLANARITY_H
#define CSTREAMS_CCD_COPLANARITY_H
/* When a query's four points can be coplanar.
 *
 * A vertex touching a face, or an edge touching an edge, puts the four points of the
 * query in one plane: g(t) = ((x1 - x0) x (x2 - x0)) . (x3 - x0) vanishes at every time
 * of contact. With the points moving linearly, g is a cubic in t (the non-penetration
 * filter's, filter.h). Its coefficients are computed once in interval arithmetic
 * rounded outward, so they hold for the exact inputs, and kept as midpoints c[k] and
 * the sum of their radii. Over times [t0, t1] around their middle m, at most h away
 * from it, the midpoint cubic p moves from p(m) by at most
 * |p'(m)| h + |p''(m)| h^2 / 2 + |c[3]| h^3 (its Taylor series ends there), and g stays
 * within the radii of p: where |p(m)| is larger than all of that, g keeps its sign and
 * no time of [t0, t1] is a contact. This only holds without a minimum separation:
 * points closer than it count as a contact without being coplanar. */
#include "filter.h"

/* How far the search narrows the times, and how many intervals it tries before it
 * keeps the rest of the step whole. In single precision the cubic solver's guess
 * (refine.cl) already prunes most late boxes, and a deeper search costs more than it
 * saves (H200: cloth-ball 3.02 ms at depth 6, 3.05 at 15; n-body 3.69 and 4.10); in
 * double it saves most of the refinement. */
#if CS_REAL_DOUBLE
#define CS_COPLANAR_DEPTH 15
#define CS_COPLANAR_TRIES 64
#else
#define CS_COPLANAR_DEPTH 6
#define CS_COPLANAR_TRIES 8
#endif
#define CS_COPLANAR_RUNS 3 /* as many separate roots as a cubic has */

typedef struct {
  real c[4];   /* c[0] + c[1] t + c[2] t^2 + c[3] t^3 */
  real radius; /* at least the sum of the coefficients' radii */
} cs_coplanarity;

/* g's coefficients (filter.h) as midpoints and the sum of their radii. */
inline cs_coplanarity cs_coplanarity_of(const cs_query* q, const int vertex_face)
{
  cs_interval c[4];
  cs_coplanarity_cubic(q, vertex_face, c);
  cs_coplanarity g;
  g.radius = 0;
  for (int k = 0; k < 4; ++k) {
    g.c[k] = (real)0.5 * (c[k].lo + c[k].hi);
    g.radius = cs_up(g.radius + cs_up(fmax(c[k].hi - g.c[k], g.c[k] - c[k].lo)));
  }
  return g;
}

/* Whether g certainly keeps its sign over [t0, t1] (0 <= t0 < t1 <= 1). The roundings
 * of the three Horner evaluations stay under 18 CS_EPS times the sum of |c[k]| (t and
 * h are at most 1), covered by 64; those of the sum by the factor. */
inline int cs_never_coplanar(const cs_coplanarity* g, const real t0, const real t1)
{
  const real m = (real)0.5 * (t0 + t1), h = cs_up(fmax(t1 - m, m - t0));
  const real p = ((g->c[3] * m + g->c[2]) * m + g->c[1]) * m + g->c[0];
  const real slope = ((real)3 * g->c[3] * m + (real)2 * g->c[2]) * m + g->c[1];
  const real bend = (real)6 * g->c[3] * m + (real)2 * g->c[2];
  const real sum = fabs(g->c[0]) + fabs(g->c[1]) + fabs(g->c[2]) + fabs(g->c[3]);
  const real moved = (fabs(slope) + ((real)0.5 * fabs(bend) + fabs(g->c[3]) * h) * h) * h;
  const real reach = (moved + g->radius + (real)64 * CS_EPS * sum) * ((real)1 + (real)16 * CS_EPS) + (real)16 * CS_TINY;
  return fabs(p) > reach;
}

/* The runs of times at which the points may be coplanar, [lo[k], hi[k]] for k below
 * the count returned (0: never), earliest first. The step is halved depth first,
 * earliest half first, dropping what keeps g's sign; after CS_COPLANAR_TRIES intervals
 * the rest of the step is kept whole, and runs beyond the last but one merge into the
 * last. Interval (level, i) is [i 2^-level, (i + 1) 2^-level], exact in any precision. */
inline int cs_coplanar_times(const cs_query* q, const int vertex_face, real lo[CS_COPLANAR_RUNS],
                             real hi[CS_COPLANAR_RUNS])
{
  const cs_coplanarity g = cs_coplanarity_of(q, vertex_face);
  uint stack[CS_COPLANAR_DEPTH + 1]; /* level in the top 5 bits, index below */
  int top = 0, runs = 0;
  stack[0] = 0;
  for (int tries = 0; top >= 0; ++tries) {
    const uint level = stack[top] >> 27, index = stack[top] & 0x7ffffffu;
    const real size = ldexp((real)1, -(int)level), t0 = index * size, t1 = (index + 1) * size;
    if (tries == CS_COPLANAR_TRIES) {
      /* What the stack holds is the rest of the step, from t0 on. */
      if (runs > 0 && hi[runs - 1] == t0) {
        hi[runs - 1] = 1;
      } else if (runs < CS_COPLANAR_RUNS) {
        lo[runs] = t0;
        hi[runs++] = 1;
      } else {
        hi[runs - 1] = 1;
      }
      break;
    }
    --top;
    if (cs_never_coplanar(&g, t0, t1)) continue;
    if (level < CS_COPLANAR_DEPTH) {
      stack[++top] = (level + 1) << 27 | (2 * index + 1);
      stack[++top] = (level + 1) << 27 | (2 * index);
    } else if (runs > 0 && (hi[runs - 1] == t0 || runs == CS_COPLANAR_RUNS)) {
      hi[runs - 1] = t1;
    } else {
      lo[runs] = t0;
      hi[runs++] = t1;
    }
  }
  return runs;
}

#endif
