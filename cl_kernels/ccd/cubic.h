#ifndef CSTREAMS_CCD_CUBIC_H
#define CSTREAMS_CCD_CUBIC_H
/* The paper's elementary test (Provot 1997, as in Collision-Streams): the times when
 * the four points are coplanar are the roots of a cubic; each root in [0, 1], earliest
 * first, is found by Newton iterations safeguarded by bisection between the cubic's
 * critical points, and the first root at which the features actually touch (vertex
 * inside the triangle, or closest points of the segments within the tolerance) is the
 * time of impact. Fast, but floating point makes it miss contacts in degenerate
 * configurations (coplanar motion, parallel edges, contact at an end point of the
 * interval); cstreams accuracy measures how often. */
#include "query.h"

inline real cs_cubic_at(const real k[4], const real t) { return ((k[3] * t + k[2]) * t + k[1]) * t + k[0]; }

inline void cs_sub3(const real a[3], const real b[3], real out[3])
{
  for (int k = 0; k < 3; ++k) out[k] = a[k] - b[k];
}
inline real cs_dot3(const real a[3], const real b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void cs_cross3(const real a[3], const real b[3], real out[3])
{
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Roots of the cubic in [0, 1], ascending; returns their count (at most 3). */
inline int cs_cubic_roots(const real k[4], real roots[3])
{
  real ends[4];
  int n = 0;
  ends[n++] = 0;
  /* Critical points split [0, 1] into pieces on which the cubic is monotone. */
  const real a = 3 * k[3], b = 2 * k[2], c = k[1];
  real crit[2];
  int nc = 0;
  if (a != 0) {
    const real disc = b * b - 4 * a * c;
    if (disc >= 0) {
      const real s = sqrt(disc);
      real r1 = (-b - s) / (2 * a), r2 = (-b + s) / (2 * a);
      if (r1 > r2) {
        const real tmp = r1;
        r1 = r2;
        r2 = tmp;
      }
      crit[nc++] = r1;
      crit[nc++] = r2;
    }
  } else if (b != 0) {
    crit[nc++] = -c / b;
  }
  for (int i = 0; i < nc; ++i)
    if (crit[i] > 0 && crit[i] < 1) ends[n++] = crit[i];
  ends[n++] = 1;

  int count = 0;
  for (int i = 0; i + 1 < n; ++i) {
    real lo = ends[i], hi = ends[i + 1];
    real flo = cs_cubic_at(k, lo), fhi = cs_cubic_at(k, hi);
    if (flo == 0) {
      if (count == 0 || roots[count - 1] != lo) roots[count++] = lo;
      continue;
    }
    if (i + 2 == n && fhi == 0) {
      roots[count++] = hi;
      continue;
    }
    if ((flo < 0) == (fhi < 0)) continue;
    real t = (real)0.5 * (lo + hi);
    for (int it = 0; it < 48; ++it) {
      const real ft = cs_cubic_at(k, t);
      if (ft == 0) break;
      if ((ft < 0) == (flo < 0)) lo = t;
      else hi = t;
      const real df = (3 * k[3] * t + 2 * k[2]) * t + k[1];
      real next = df != 0 ? t - ft / df : (real)0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = (real)0.5 * (lo + hi);
      if (next == t) break;
      t = next;
    }
    if (count < 3) roots[count++] = t;
  }
  return count;
}

/* q: the query's 24 coordinates, points x[0..3] at t = 0 then at t = 1. */
inline void cs_point_at(const real* q, const int point, const real t, real out[3])
{
  for (int k = 0; k < 3; ++k) {
    const real x0 = q[point * 3 + k], x1 = q[(point + 4) * 3 + k];
    out[k] = x0 + (x1 - x0) * t;
  }
}

/* Do the features touch at time t (within eps, in scene units)? *u_at and *v_at: where,
 * as the parameters of the contact function (trilinear.h): the vertex's barycentric
 * coordinates along f1 - f0 and f2 - f0, or the closest points' along each edge. */
inline int cs_touching(const real* q, const int vertex_face, const real t, const real eps, real* u_at, real* v_at)
{
  real x[4][3];
  for (int i = 0; i < 4; ++i) cs_point_at(q, i, t, x[i]);
  if (vertex_face) { /* barycentric coordinates of the vertex's projection */
    real e0[3], e1[3], d[3];
    cs_sub3(x[2], x[1], e0);
    cs_sub3(x[3], x[1], e1);
    cs_sub3(x[0], x[1], d);
    const real d00 = cs_dot3(e0, e0), d01 = cs_dot3(e0, e1), d11 = cs_dot3(e1, e1);
    const real d20 = cs_dot3(d, e0), d21 = cs_dot3(d, e1);
    const real denom = d00 * d11 - d01 * d01;
    if (!(denom > 0)) return 0;
    const real v = (d11 * d20 - d01 * d21) / denom, w = (d00 * d21 - d01 * d20) / denom;
    const real slack = eps / sqrt(fmax(d00, d11));
    if (v < -slack || w < -slack || v + w > 1 + slack) return 0;
    real gap[3];
    for (int k = 0; k < 3; ++k) gap[k] = d[k] - v * e0[k] - w * e1[k];
    *u_at = v;
    *v_at = w;
    return cs_dot3(gap, gap) <= eps * eps;
  }
  /* closest points of two segments (Ericson, Real-Time Collision Detection 5.1.9) */
  real d1[3], d2[3], r[3];
  cs_sub3(x[1], x[0], d1);
  cs_sub3(x[3], x[2], d2);
  cs_sub3(x[0], x[2], r);
  const real a = cs_dot3(d1, d1), e = cs_dot3(d2, d2), f = cs_dot3(d2, r);
  real s = 0, u = 0;
  if (a > 0 || e > 0) {
    if (a <= 0) {
      u = clamp(f / e, (real)0, (real)1);
    } else {
      const real c = cs_dot3(d1, r);
      if (e <= 0) {
        s = clamp(-c / a, (real)0, (real)1);
      } else {
        const real b = cs_dot3(d1, d2), denom = a * e - b * b;
        s = denom > 0 ? clamp((b * f - c * e) / denom, (real)0, (real)1) : 0;
        u = (b * s + f) / e;
        if (u < 0) {
          u = 0;
          s = clamp(-c / a, (real)0, (real)1);
        } else if (u > 1) {
          u = 1;
          s = clamp((b - c) / a, (real)0, (real)1);
        }
      }
    }
  }
  real gap[3];
  for (int k = 0; k < 3; ++k) gap[k] = (x[0][k] + d1[k] * s) - (x[2][k] + d2[k] * u);
  *u_at = s;
  *v_at = u;
  return cs_dot3(gap, gap) <= eps * eps;
}

/* A time before which cs_touching(q, vertex_face, t, eps) fails: the features' boxes
 * stay more than `margin` apart along an axis. Each box moves no faster than its
 * fastest point, so a gap g0 at t = 0 closing at rate r > 0 stays above the margin
 * until (g0 - margin) / r; a gap that does not close stays. 2 where some gap stays
 * above the margin through the step, 0 where none starts above it. cs_touching passes
 * only where the points are within 3 eps: its projection may leave the face by eps
 * along each edge. */
inline real cs_apart_until(const real* q, const int vertex_face, const real margin)
{
  const int split = vertex_face ? 1 : 2;
  real until = 0;
  for (int k = 0; k < 3; ++k) {
    real lo[2], hi[2], slow[2], fast[2]; /* per side: box at 0, least and most velocity */
    for (int side = 0; side < 2; ++side) {
      const int first = side ? split : 0, last = side ? 4 : split;
      lo[side] = hi[side] = q[3 * first + k];
      slow[side] = fast[side] = q[3 * (first + 4) + k] - q[3 * first + k];
      for (int i = first + 1; i < last; ++i) {
        const real x = q[3 * i + k], v = q[3 * (i + 4) + k] - x;
        lo[side] = fmin(lo[side], x);
        hi[side] = fmax(hi[side], x);
        slow[side] = fmin(slow[side], v);
        fast[side] = fmax(fast[side], v);
      }
    }
    for (int above = 0; above < 2; ++above) {
      const real gap = lo[above] - hi[1 - above] - margin, closing = fast[1 - above] - slow[above];
      if (gap > 0) until = fmax(until, closing > 0 ? gap / closing : 2);
    }
  }
  return until;
}

/* The margin for cs_apart_until: cs_touching's 3 eps, and room for the rounding of
 * the points it moves and of the bound itself (CS_EPS per operation on coordinates of
 * magnitude scale). */
inline real cs_touching_margin(const real eps, const real scale) { return 3 * eps + 64 * CS_EPS * scale; }

/* at: the time of impact and where (u, v as cs_touching gives them). */
inline uint cs_cubic(const real* q, const int vertex_face, const real tolerance, real at[3])
{
  real x0[4][3], v[4][3];
  real scale = 0;
  for (int i = 0; i < 4; ++i) {
    cs_point_at(q, i, 0, x0[i]);
    real x1[3];
    cs_point_at(q, i, 1, x1);
    cs_sub3(x1, x0[i], v[i]);
    for (int k = 0; k < 3; ++k) scale = fmax(scale, fmax(fabs(x0[i][k]), fabs(x1[k])));
  }
  /* f(t) = ((x_b - x_a) x (x_c - x_a)) . (x_d - x_a), as in filter.h */
  const int a = vertex_face ? 1 : 0, bi = vertex_face ? 2 : 1, ci = vertex_face ? 3 : 2, di = vertex_face ? 0 : 3;
  real A0[3], Av[3], B0[3], Bv[3], C0[3], Cv[3];
  cs_sub3(x0[bi], x0[a], A0);
  cs_sub3(v[bi], v[a], Av);
  cs_sub3(x0[ci], x0[a], B0);
  cs_sub3(v[ci], v[a], Bv);
  cs_sub3(x0[di], x0[a], C0);
  cs_sub3(v[di], v[a], Cv);
  real n0[3], n1a[3], n1b[3], n1[3], n2[3];
  cs_cross3(A0, B0, n0);
  cs_cross3(A0, Bv, n1a);
  cs_cross3(Av, B0, n1b);
  for (int k = 0; k < 3; ++k) n1[k] = n1a[k] + n1b[k];
  cs_cross3(Av, Bv, n2);
  const real k[4] = {cs_dot3(n0, C0), cs_dot3(n0, Cv) + cs_dot3(n1, C0), cs_dot3(n1, Cv) + cs_dot3(n2, C0),
                     cs_dot3(n2, Cv)};
  real roots[3];
  const int count = cs_cubic_roots(k, roots);
  const real eps = tolerance * fmax(scale, CS_TINY);
  for (int i = 0; i < count; ++i)
    if (cs_touching(q, vertex_face, roots[i], eps, &at[1], &at[2])) {
      at[0] = roots[i];
      return CS_COLLIDES;
    }
  at[0] = 1;
  return CS_SEPARATE;
}

#endif
