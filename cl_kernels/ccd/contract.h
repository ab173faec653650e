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
  /* Every sum of non-negative terms below is rounded, and is at most ten roundings
   * deep: `grow` covers that; the CS_TINY terms cover products flushed to zero. */
  const real grow = (real)1 + (real)32 * CS_EPS;
  real fm[3], fr[3], jm[3][3], jr[3][3];
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

  const real cof[3][3] = {{jm[1][1] * jm[2][2] - jm[1][2] * jm[2][1], jm[1][2] * jm[2][0] - jm[1][0] * jm[2][2],
                           jm[1][0] * jm[2][1] - jm[1][1] * jm[2][0]},
                          {jm[0][2] * jm[2][1] - jm[0][1] * jm[2][2], jm[0][0] * jm[2][2] - jm[0][2] * jm[2][0],
                           jm[0][1] * jm[2][0] - jm[0][0] * jm[2][1]},
                          {jm[0][1] * jm[1][2] - jm[0][2] * jm[1][1], jm[0][2] * jm[1][0] - jm[0][0] * jm[1][2],
                           jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0]}};
  const real det = jm[0][0] * cof[0][0] + jm[0][1] * cof[0][1] + jm[0][2] * cof[0][2];
  if (!(fabs(det) > CS_TINY) || !isfinite(det)) return 1; /* no useful Y: the box stays as it is */
  const real inverse = (real)1 / det;
  real y[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) y[i][k] = cof[k][i] * inverse;

  real narrow_lo[3], narrow_hi[3];
  for (int i = 0; i < 3; ++i) {
    /* (I - Y J)(X - c) over a box symmetric about c: |I - Y J| row i times the radii.
     * Each entry is its computed middle, within 8 CS_EPS of the size of its terms,
     * plus |Y| times J's radii. */
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
    const real radius =
        (spread + step_reach + (real)8 * CS_EPS * step_size + (real)2 * CS_EPS * fabs(at)) * grow + (real)64 * CS_TINY;
    const real k_lo = cs_down(at - radius), k_hi = cs_up(at + radius);
    narrow_lo[i] = lo[i];
    narrow_hi[i] = hi[i];
    if (!isfinite(k_lo) || !isfinite(k_hi)) continue; /* Y too large to say anything along i */
    narrow_lo[i] = fmax(lo[i], k_lo);
    narrow_hi[i] = fmin(hi[i], k_hi);
    if (narrow_lo[i] > narrow_hi[i]) return 0;
  }
  *b = cs_box_of(narrow_lo, narrow_hi);
  return 1;
}

#endif
