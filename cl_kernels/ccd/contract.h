#ifndef CSTREAMS_CCD_CONTRACT_H
#define CSTREAMS_CCD_CONTRACT_H
/* Narrowing a box of parameters to where F can still reach zero (or the separation),
 * with Krawczyk's operator. Bisection alone needs about twenty halvings per parameter
 * to bring a box around a root down to the tolerance, and keeps the neighbours of
 * the root's box alive all the way; once a box is small enough for F to be nearly
 * linear on it, Krawczyk's operator shrinks it quadratically and empties the
 * neighbours, and it never removes a point where F meets the separation.
 *
 * For the centre c of box X, bounds J of F's Jacobian over X and any matrix Y, every
 * x in X with F(x) in S = [-separation, separation]^3 lies in
 *   K = c - Y (F(c) - S) + (I - Y J)(X - c)
 * (the mean value theorem, row by row). Y is the inverse of J's middle, so that
 * I - Y J is small; it needs no rigour, the bounds around it do. */
#include "trilinear.h"

/* m[r][c], picked among constant indices: a private array indexed by a run-time value
 * is kept in memory instead of registers. */
inline real cs_entry(const real m[3][3], const int r, const int c)
{
  const real r0 = c == 0 ? m[0][0] : c == 1 ? m[0][1] : m[0][2];
  const real r1 = c == 0 ? m[1][0] : c == 1 ? m[1][1] : m[1][2];
  const real r2 = c == 0 ? m[2][0] : c == 1 ? m[2][1] : m[2][2];
  return r == 0 ? r0 : r == 1 ? r1 : r2;
}

/* Y inverting J's largest 2 x 2 block, in two coordinates and two parameters, and
 * leaving the third parameter alone: K still holds every zero, that parameter's reach
 * entering through (I - Y J)(X - c). The block left after taking out row k and column i
 * of J has determinant (-1)^(k + i) cof[k][i]. Returns 0 where every block is singular. */
inline int cs_block_inverse(const real jm[3][3], const real cof[3][3], real y[3][3])
{
  int skip = 0, free = 0;
  real largest = -1;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i)
      if (fabs(cof[k][i]) > largest) {
        largest = fabs(cof[k][i]);
        skip = k;
        free = i;
      }
  const real minor = cs_entry(cof, skip, free);
  if (!(fabs(minor) > CS_TINY) || !isfinite(minor)) return 0;
  const int k1 = skip == 0 ? 1 : 0, k2 = skip == 2 ? 1 : 2, p1 = free == 0 ? 1 : 0, p2 = free == 2 ? 1 : 2;
  const real inverse = ((skip + free) % 2 ? (real)-1 : (real)1) / minor;
  const real a = cs_entry(jm, k1, p1), b = cs_entry(jm, k1, p2), c = cs_entry(jm, k2, p1), d = cs_entry(jm, k2, p2);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      y[i][k] = i == p1   ? (k == k1 ? d : k == k2 ? -b : (real)0) * inverse
                : i == p2 ? (k == k1 ? -c : k == k2 ? a : (real)0) * inverse
                          : (real)0;
  return 1;
}

/* Every sum of non-negative terms below is rounded, and is at most ten roundings deep:
 * CS_CONTRACT_GROW covers that; the CS_TINY terms cover products flushed to zero. */
#define CS_CONTRACT_GROW ((real)1 + (real)32 * CS_EPS)

/* F over the box of centre `mid`, radii `rad` and upper corner `hi`, as a middle and a
 * radius: its value at the centre (fm, fr, the radius widened by the separation) and
 * its slopes (jm, jr). */
inline void cs_contract_linearise(const cs_trilinear* f, const real mid[3], const real rad[3], const real hi[3],
                                  const real separation, real fm[3], real fr[3], real jm[3][3], real jr[3][3])
{
  const real grow = CS_CONTRACT_GROW;
  for (int k = 0; k < 3; ++k) {
    fm[k] = cs_trilinear_at(f, k, mid[0], mid[1], mid[2], &fr[k]);
    fr[k] += separation;
    /* F's slopes: their middles at the centre, their radii the reach of the other
     * parameters over the box plus the coefficients' error weights, which also cover
     * the rounding of the middles. */
    cs_trilinear_slopes(f, k, mid, jm[k]);
    const real D = f->c[3][k], G = f->c[5][k];
    jr[k][0] = (rad[1] * fabs(D) + rad[2] * fabs(G) + f->w[1][k] + hi[1] * f->w[3][k] + hi[2] * f->w[5][k]) * grow +
               (real)8 * CS_TINY;
    jr[k][1] = (rad[0] * fabs(D) + f->w[2][k] + hi[0] * f->w[3][k]) * grow + (real)8 * CS_TINY;
    jr[k][2] = (rad[0] * fabs(G) + f->w[4][k] + hi[0] * f->w[5][k]) * grow + (real)8 * CS_TINY;
  }
}

/* Row i of K: where (I - Y J)(X - c) over a box symmetric about c, |I - Y J| row i times
 * the radii, and Y F(c) put X. Each entry of I - Y J is its computed middle, within
 * 8 CS_EPS of the size of its terms, plus |Y| times J's radii. */
inline void cs_contract_row(const int i, const real y[3][3], const real jm[3][3], const real jr[3][3],
                            const real fm[3], const real fr[3], const real mid[3], const real rad[3], real* k_lo,
                            real* k_hi)
{
  real spread = 0;
  for (int j = 0; j < 3; ++j) {
    real entry = i == j ? (real)1 : (real)0, size = entry, reach = 0;
    for (int k = 0; k < 3; ++k) {
      const real p = y[i][k] * jm[k][j];
      entry -= p;
      size += fabs(p);
      reach += fabs(y[i][k]) * jr[k][j];
    }
    spread += (fabs(entry) + reach + (real)8 * CS_EPS * size) * rad[j];
  }
  real step = 0, step_size = 0, step_reach = 0;
  for (int k = 0; k < 3; ++k) {
    const real p = y[i][k] * fm[k];
    step += p;
    step_size += fabs(p);
    step_reach += fabs(y[i][k]) * fr[k];
  }
  const real at = mid[i] - step;
  const real radius = (spread + step_reach + (real)8 * CS_EPS * step_size + (real)2 * CS_EPS * fabs(at)) *
                          CS_CONTRACT_GROW +
                      (real)64 * CS_TINY;
  *k_lo = cs_down(at - radius);
  *k_hi = cs_up(at + radius);
}

/* Narrows *b to its intersection with K. Returns 0 when that is empty: F misses S on
 * the box. */
inline int cs_trilinear_contract(const cs_trilinear* f, cs_box* b, const real separation)
{
  const real lo[3] = {b->t0, b->u0, b->v0}, hi[3] = {b->t1, b->u1, b->v1};
  real mid[3], rad[3];
  for (int i = 0; i < 3; ++i) {
    mid[i] = (real)0.5 * (lo[i] + hi[i]);
    rad[i] = cs_up(fmax(hi[i] - mid[i], mid[i] - lo[i]));
  }
  real fm[3], fr[3], jm[3][3], jr[3][3];
  cs_contract_linearise(f, mid, rad, hi, separation, fm, fr, jm, jr);
  const real cof[3][3] = {{jm[1][1] * jm[2][2] - jm[1][2] * jm[2][1], jm[1][2] * jm[2][0] - jm[1][0] * jm[2][2],
                           jm[1][0] * jm[2][1] - jm[1][1] * jm[2][0]},
                          {jm[0][2] * jm[2][1] - jm[0][1] * jm[2][2], jm[0][0] * jm[2][2] - jm[0][2] * jm[2][0],
                           jm[0][1] * jm[2][0] - jm[0][0] * jm[2][1]},
                          {jm[0][1] * jm[1][2] - jm[0][2] * jm[1][1], jm[0][2] * jm[1][0] - jm[0][0] * jm[1][2],
                           jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0]}};
  const real det = jm[0][0] * cof[0][0] + jm[0][1] * cof[0][1] + jm[0][2] * cof[0][2];
  /* Y is J's inverse where J has one. Where J is singular (F does not vary along some
   * parameter: features that move together; or along some coordinate: a query in a
   * plane of the axes), or where that inverse narrows nothing (J nearly singular, as for
   * nearly parallel edges, whose inverse magnifies every error), Y inverts J's largest
   * 2 x 2 block instead (cs_block_inverse). Cloth-funnel in double: 17 rounds of
   * refinement -> 7; cloth-ball 6 -> 3. (The block instead of the inverse wherever J is
   * nearly singular gave up narrowing the inverse did: more rounds, false positives.) */
  real y[3][3];
  int whole = fabs(det) > CS_TINY && isfinite(det);
  if (whole) {
    const real inverse = (real)1 / det;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) y[i][k] = cof[k][i] * inverse;
  } else if (!cs_block_inverse(jm, cof, y)) {
    return 1; /* no useful Y: the box stays as it is */
  }

  real narrow_lo[3], narrow_hi[3];
  for (;;) {
    for (int i = 0; i < 3; ++i) {
      real k_lo, k_hi;
      cs_contract_row(i, y, jm, jr, fm, fr, mid, rad, &k_lo, &k_hi);
      narrow_lo[i] = lo[i];
      narrow_hi[i] = hi[i];
      if (!isfinite(k_lo) || !isfinite(k_hi)) continue; /* Y too large to say anything along i */
      narrow_lo[i] = fmax(lo[i], k_lo);
      narrow_hi[i] = fmin(hi[i], k_hi);
      if (narrow_lo[i] > narrow_hi[i]) return 0;
    }
    const int narrowed = narrow_lo[0] > lo[0] || narrow_hi[0] < hi[0] || narrow_lo[1] > lo[1] || narrow_hi[1] < hi[1] ||
                         narrow_lo[2] > lo[2] || narrow_hi[2] < hi[2];
    if (narrowed || !whole || !cs_block_inverse(jm, cof, y)) break;
    whole = 0;
  }
  *b = cs_box_of(narrow_lo, narrow_hi);
  return 1;
}

#endif
