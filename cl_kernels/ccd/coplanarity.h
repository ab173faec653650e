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

/* How far the search narrows the times: levels of eighths (2^-15 of the step in
 * double, 1/8 in single), and how many intervals it cuts into eighths before it keeps
 * the rest of the step whole. In double it saves most of the refinement (16 cuts:
 * cloth-ball 2.59 ms, 8: 2.82, 24: 2.63). In single precision a deeper search costs more
 * than it saves: with inputs rounded to float, whose late boxes the cubic solver's guess
 * (refine.cl) prunes (H200, device ms, at 1/8 (1 cut) / 1/64 (2 cuts) / 1/64 (4 cuts):
 * cloth-ball 2.95 / 2.97 / 2.92, n-body 3.66 / 3.71 / 3.78), and with floats taken as the
 * exact input (H100, at 1/8 / 1/64 (4 cuts) / 1/512 (16 cuts): cloth-ball 2.40 / 2.31 /
 * 2.34, n-body 3.42 / 3.50 / 3.71, cloth-funnel 0.59 / 0.61 / 0.62). */
#if CS_REAL_DOUBLE
#define CS_COPLANAR_LEVELS 5
#define CS_COPLANAR_TRIES 16
#else
#define CS_COPLANAR_LEVELS 1
#define CS_COPLANAR_TRIES 1
#endif
#define CS_COPLANAR_RUNS 3 /* as many separate roots as a cubic has */

typedef struct {
  real c[4];   /* c[0] + c[1] t + c[2] t^2 + c[3] t^3 */
  real radius; /* at least the sum of the coefficients' radii */
} cs_coplanarity;

/* g's coefficients (cs_coplanarity_cubic, filter.h) as midpoints and the sum of their
 * radii. */
inline cs_coplanarity cs_coplanarity_of(const cs_interval c[4])
{
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

/* Which eighths of interval `index` of level `level` ([index 8^-level, (index + 1)
 * 8^-level], exact in any precision) g may vanish on: bit k for the k-th. The eight
 * tests are independent of one another, so they run side by side where a halving
 * search waits on each in turn, and in as long a search they leave narrower runs
 * (cloth-ball in double: 6 rounds of refinement after them, 18 after halving). */
inline uint cs_coplanar_eighths(const cs_coplanarity* g, const int level, const uint index)
{
  const real size = ldexp((real)1, -3 * (level + 1));
  uint mask = 0;
  for (uint k = 0; k < 8; ++k) {
    const uint i = 8 * index + k;
    if (!cs_never_coplanar(g, i * size, (i + 1) * size)) mask |= 1u << k;
  }
  return mask;
}

/* Adds [t0, t1] (no earlier than any run so far) to the runs, joining the last one
 * where they meet and merging into the last one beyond CS_COPLANAR_RUNS. */
inline void cs_add_run(real lo[CS_COPLANAR_RUNS], real hi[CS_COPLANAR_RUNS], int* runs, const real t0, const real t1)
{
  if (*runs > 0 && (hi[*runs - 1] == t0 || *runs == CS_COPLANAR_RUNS)) {
    hi[*runs - 1] = t1;
  } else {
    lo[*runs] = t0;
    hi[(*runs)++] = t1;
  }
}

/* The runs of times at which the points may be coplanar, [lo[k], hi[k]] for k below
 * the count returned (0: never), earliest first. Depth first, earliest eighth first,
 * over the eighths g may vanish on; after cutting CS_COPLANAR_TRIES intervals into
 * eighths, the rest of the step is kept whole. The eighths still to visit at each
 * level are bits of one mask and the way down digits of one index, so the search holds
 * no stack in memory. */
inline int cs_coplanar_times(const cs_interval c[4], real lo[CS_COPLANAR_RUNS], real hi[CS_COPLANAR_RUNS])
{
  const cs_coplanarity g = cs_coplanarity_of(c);
  int runs = 0;
  if (cs_never_coplanar(&g, 0, 1)) return 0;
  ulong pending = cs_coplanar_eighths(&g, 0, 0); /* 8 bits a level: the eighths left there */
  uint index = 0;                                  /* the interval at `level`, 3 bits a level */
  int level = 0, tries = 1;
  for (;;) {
    const uint left = (uint)(pending >> (8 * level)) & 0xffu;
    if (left == 0) {
      if (level == 0) break;
      --level;
      index >>= 3;
      continue;
    }
    const uint k = 31 - clz(left & (0u - left)); /* the earliest eighth left */
    pending &= ~((ulong)1 << (8 * level + k));
    const uint child = 8 * index + k;
    const real size = ldexp((real)1, -3 * (level + 1)), t0 = child * size;
    if (level + 1 == CS_COPLANAR_LEVELS) {
      cs_add_run(lo, hi, &runs, t0, t0 + size);
    } else if (tries == CS_COPLANAR_TRIES) {
      cs_add_run(lo, hi, &runs, t0, 1); /* every eighth left starts later */
      break;
    } else {
      ++level;
      index = child;
      pending |= (ulong)cs_coplanar_eighths(&g, level, index) << (8 * level);
      ++tries;
    }
  }
  return runs;
}

#endif
