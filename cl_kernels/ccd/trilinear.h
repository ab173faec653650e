#ifndef CSTREAMS_CCD_TRILINEAR_H
#define CSTREAMS_CCD_TRILINEAR_H
/* The contact function of a query as a trilinear polynomial, and cheap rigorous
 * bounds of it over a box of parameters.
 *
 * Vertex-face, F = p - f0 - u (f1 - f0) - v (f2 - f0), and edge-edge,
 * F = a0 + u (a1 - a0) - b0 - v (b1 - b0), with every point moving linearly in t, are
 * both F(t, u, v) = A + t B + u C + t u D + v E + t v G. The six coefficients are
 * computed once per query in interval arithmetic rounded outward (so they hold for the
 * exact inputs) and kept as a midpoint and an error weight: the radius plus a bound
 * on the rounding of one term (seven roundings of the evaluation, 4 CS_EPS > gamma_7).
 * A box's corners are then evaluated in plain arithmetic, and at a corner (t, u, v)
 * the exact F is within the same polynomial of the weights of the computed value: each
 * corner's error scales with its own terms, as interval arithmetic's would, which
 * matters where F passes within rounding distance of zero.
 * F is trilinear, so over the box it lies in the hull of its corner values. This costs
 * a fraction of evaluating the corners in interval arithmetic. */
#include "query.h"

typedef struct {
  real t0, t1, u0, u1, v0, v1;
} cs_box;

/* The box from its lower and upper corner, (t, u, v) each. */
inline cs_box cs_box_of(const real lo[3], const real hi[3])
{
  const cs_box b = {lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]};
  return b;
}

/* The whole parameter box. */
inline cs_box cs_root_box(void)
{
  const cs_box root = {0, 1, 0, 1, 0, 1};
  return root;
}

/* c[j][k]: coefficient j (A, B, C, D, E, G) of coordinate k; w[j][k] its error weight. */
typedef struct {
  real c[6][3];
  real w[6][3];
} cs_trilinear;

inline cs_trilinear cs_make_trilinear(const cs_query* q, const int vertex_face)
{
  cs_trilinear f;
  /* Point roles: vertex-face 0 p, 1 f0, 2 f1, 3 f2; edge-edge 0 a0, 1 a1, 2 b0, 3 b1.
   * A = x_a - x_b, C = x_c0 - x_c1, E = x_e0 - x_e1 at the start; B, D, G the same of the
   * motions. Points are picked by constant indices only: a private array indexed by a
   * run-time value is kept in memory instead of registers. */
  for (int k = 0; k < 3; ++k) {
    const cs_interval p0 = q->x[0][k], p1 = q->x[1][k], p2 = q->x[2][k], p3 = q->x[3][k];
    const cs_interval m0 = cs_isub(q->x[4][k], p0), m1 = cs_isub(q->x[5][k], p1), m2 = cs_isub(q->x[6][k], p2),
                      m3 = cs_isub(q->x[7][k], p3);
    cs_interval co[6];
    if (vertex_face) {
      co[0] = cs_isub(p0, p1);
      co[1] = cs_isub(m0, m1);
      co[2] = cs_isub(p1, p2);
      co[3] = cs_isub(m1, m2);
      co[4] = cs_isub(p1, p3);
      co[5] = cs_isub(m1, m3);
    } else {
      co[0] = cs_isub(p0, p2);
      co[1] = cs_isub(m0, m2);
      co[2] = cs_isub(p1, p0);
      co[3] = cs_isub(m1, m0);
      co[4] = cs_isub(p2, p3);
      co[5] = cs_isub(m2, m3);
    }
    for (int j = 0; j < 6; ++j) {
      const real mid = (real)0.5 * (co[j].lo + co[j].hi);
      f.c[j][k] = mid;
      f.w[j][k] = cs_up(cs_up(fmax(co[j].hi - mid, mid - co[j].lo)) + cs_up(fabs(mid) * (real)4 * CS_EPS));
    }
  }
  return f;
}

/* Coefficients j and j + 1 of coordinate k from exact points a and b: the start
 * difference a - b and the motion difference (a1 - a0) - (b1 - b0), given the points
 * at t = 0 and the motions ma, mb as computed. Each difference rounded to nearest lies
 * within CS_EPS / 2 of its value (or CS_TINY, where it flushed) from the exact one, so
 * the weights need no intervals: EPS |c|, twice that, covers the rounding of c and of
 * the weight itself, EPS (|ma| + |mb|) the motions', and 4 EPS |c| the evaluation's,
 * as in cs_make_trilinear, whose weights for the same points these match to a few
 * ulps. */
inline void cs_exact_difference(const real a, const real b, const real ma, const real mb, const int j, const int k,
                                cs_trilinear* f)
{
  const real start = a - b, motion = ma - mb;
  f->c[j][k] = start;
  f->c[j + 1][k] = motion;
  f->w[j][k] = cs_up(fabs(start) * ((real)5 * CS_EPS) + CS_TINY);
  f->w[j + 1][k] = cs_up(fabs(motion) * ((real)5 * CS_EPS) + (fabs(ma) + fabs(mb)) * CS_EPS + (real)3 * CS_TINY);
}

/* cs_make_trilinear of exact points, q as cs_pair_points gives them (x0's four, then
 * x1's): the same coefficients, with weights bounded from the computed values rather
 * than carried through interval arithmetic, for a fraction of its work. */
inline cs_trilinear cs_make_exact_trilinear(const real q[24], const int vertex_face)
{
  cs_trilinear f;
  for (int k = 0; k < 3; ++k) {
    const real p0 = q[k], p1 = q[3 + k], p2 = q[6 + k], p3 = q[9 + k];
    const real m0 = q[12 + k] - p0, m1 = q[15 + k] - p1, m2 = q[18 + k] - p2, m3 = q[21 + k] - p3;
    if (vertex_face) {
      cs_exact_difference(p0, p1, m0, m1, 0, k, &f);
      cs_exact_difference(p1, p2, m1, m2, 2, k, &f);
      cs_exact_difference(p1, p3, m1, m3, 4, k, &f);
    } else {
      cs_exact_difference(p0, p2, m0, m2, 0, k, &f);
      cs_exact_difference(p1, p0, m1, m0, 2, k, &f);
      cs_exact_difference(p2, p3, m2, m3, 4, k, &f);
    }
  }
  return f;
}

/* The error bound of F_k at a point from e, the error weights' sum there. That sum is
 * of non-negative terms: eleven roundings at most, covered by 8 CS_EPS; and up to eleven
 * results flushed to zero in the value and as many in the error. A macro, for one
 * point (real) or a box's eight corners (real8) alike. */
#define CS_TRILINEAR_ERROR(e) ((e) * ((real)1 + (real)8 * CS_EPS) + (real)32 * CS_TINY)

/* Coordinate k of A + t B + u C + t u D + v E + t v G with the coefficients (or their
 * weights) x, summed in this order, at one point or at eight. */
#define CS_TRILINEAR_SUM(x, k, t, u, tu, v, tv) \
  ((x)[0][k] + (t) * (x)[1][k] + (u) * (x)[2][k] + (tu) * (x)[3][k] + (v) * (x)[4][k] + (tv) * (x)[5][k])

/* F_k at parameters t, u, v >= 0 as computed, and *error, the bound on how far the
 * exact F_k lies from it. */
inline real cs_trilinear_at(const cs_trilinear* f, const int k, const real t, const real u, const real v,
                            real* error)
{
  const real tu = t * u, tv = t * v;
  *error = CS_TRILINEAR_ERROR(CS_TRILINEAR_SUM(f->w, k, t, u, tu, v, tv));
  return CS_TRILINEAR_SUM(f->c, k, t, u, tu, v, tv);
}

/* F_k's slopes along t, u and v at the parameters `at`, as computed (no error bound):
 * dF/dt = B + u D + v G, dF/du = C + t D, dF/dv = E + t G. */
inline void cs_trilinear_slopes(const cs_trilinear* f, const int k, const real at[3], real slope[3])
{
  slope[0] = f->c[1][k] + at[1] * f->c[3][k] + at[2] * f->c[5][k];
  slope[1] = f->c[2][k] + at[0] * f->c[3][k];
  slope[2] = f->c[4][k] + at[0] * f->c[5][k];
}

/* The parameter along which F varies most, of spreads as cs_trilinear_bounds gives. */
inline int cs_most_varied(const real spread[3])
{
  return spread[0] >= spread[1] ? (spread[0] >= spread[2] ? 0 : 2) : (spread[1] >= spread[2] ? 1 : 2);
}

/* The smallest and the largest of several values, a number where any is (fmin, fmax). */
inline real cs_least4(const real4 x)
{
  const real2 a = fmin(x.lo, x.hi);
  return fmin(a.x, a.y);
}
inline real cs_most4(const real4 x)
{
  const real2 a = fmax(x.lo, x.hi);
  return fmax(a.x, a.y);
}
inline real cs_least8(const real8 x) { return cs_least4(fmin(x.lo, x.hi)); }
inline real cs_most8(const real8 x) { return cs_most4(fmax(x.lo, x.hi)); }

/* Whether direction d separates rigorously: d.F stays farther than `separation` times
 * |d|_1 from zero at every corner of the box (value and error as cs_trilinear_bounds_of
 * takes them). The corners go four at a time (cs_trilinear_bounds_of says why). */
inline int cs_direction_separates(real d0, real d1, real d2, const real8 value[3], const real8 error[3],
                                  const real separation)
{
  /* Scaled to a largest component of 1: any direction is as valid, and products with
   * tiny directions would otherwise fall into subnormals (slow on CPUs). */
  const real largest = fmax(fabs(d0), fmax(fabs(d1), fabs(d2)));
  if (!(largest > CS_TINY * (real)0x1p24) || !isfinite(largest)) return 0;
  d0 /= largest;
  d1 /= largest;
  d2 /= largest;
  const real a0 = fabs(d0), a1 = fabs(d1), a2 = fabs(d2);
  const real norm1 = a0 + a1 + a2;
  real lo = CS_REAL_MAX, hi = -CS_REAL_MAX;
  for (int side = 0; side < 2; ++side) {
    const real4 v0 = side ? value[0].hi : value[0].lo, v1 = side ? value[1].hi : value[1].lo,
                v2 = side ? value[2].hi : value[2].lo;
    const real4 r0 = side ? error[0].hi : error[0].lo, r1 = side ? error[1].hi : error[1].lo,
                r2 = side ? error[2].hi : error[2].lo;
    const real4 dot = d0 * v0 + d1 * v1 + d2 * v2;
    /* d.F at a corner differs from dot by the inputs' share, sum |d_k| error_k, and the
     * dot product's own rounding, under 2 CS_EPS sum |d_k value_k|; the margin's own
     * five roundings are covered by the factor. */
    const real4 margin = (a0 * (r0 + (real)2 * CS_EPS * fabs(v0)) + a1 * (r1 + (real)2 * CS_EPS * fabs(v1)) +
                          a2 * (r2 + (real)2 * CS_EPS * fabs(v2))) *
                             ((real)1 + (real)8 * CS_EPS) +
                         (real)8 * CS_TINY;
    lo = fmin(lo, cs_least4(dot - margin));
    hi = fmax(hi, cs_most4(dot + margin));
  }
  const real reach = cs_up(separation * cs_up(norm1));
  return cs_down(lo) > reach || cs_up(hi) < -reach;
}

/* Bounds F over the box b from its values and error bounds at b's corners
 * (cs_trilinear_corners: component c of value[k] is F_k at corner c). Returns 0 when
 * F certainly stays farther than `separation` from zero there: along the coordinate
 * axes, along F at the box centre, or along the face (or edge pair) normal at the
 * box's middle time. Otherwise sets *width to the widest side of the bounding box of
 * F, *farthest to the largest |F_k| it allows, nearest[0] and nearest[1] to the largest
 * |F_k| at the corner where that is smallest among the corners at the box's start and
 * end time (with a positive separation only, where they matter), *first to the
 * largest |F_k| they allow at the box's first corner (t0, u0, v0) (NaN where that is
 * not a number), and spread[j] to how much F varies along parameter j (0 t, 1 u, 2 v)
 * across the box (cs_most_varied). The corners go side by side in vectors, which a
 * CPU takes several at once and a GPU one after the other (pocl: cloth-ball's screen
 * about a fifth faster, GPUs the same). The direction tests take four corners at a
 * time: with all eight, the GPU's screen held 100 registers against 80 and took a
 * quarter longer (H200). */
inline int cs_trilinear_bounds_of(const cs_trilinear* f, const cs_box b, const real8 value[3], const real8 error[3],
                                  const real separation, real* width, real* farthest, real nearest[2], real* first,
                                  real spread[3])
{
  *first = 0;
  for (int k = 0; k < 3; ++k) {
    const real at = cs_up(fabs(value[k].s0) + error[k].s0);
    if (!(at <= *first)) *first = at;
  }
  real centre[3];
  *width = 0;
  *farthest = 0;
  nearest[0] = nearest[1] = CS_REAL_MAX;
  if (separation > 0) {
    real8 reach = 0;
    for (int k = 0; k < 3; ++k) reach = fmax(reach, cs_up8(fabs(value[k]) + error[k]));
    nearest[0] = cs_least4(reach.lo);
    nearest[1] = cs_least4(reach.hi);
  }
  for (int k = 0; k < 3; ++k) {
    /* Each difference rounded to nearest: one step out covers it. */
    const real lo = cs_down(fmin(CS_REAL_MAX, cs_least8(value[k] - error[k])));
    const real hi = cs_up(fmax(-CS_REAL_MAX, cs_most8(value[k] + error[k])));
    if (lo > separation || hi < -separation) return 0;
    *width = fmax(*width, hi - lo);
    *farthest = fmax(*farthest, fmax(-lo, hi));
    const real8 x = value[k];
    centre[k] = (real)0.125 * (((((((x.s0 + x.s1) + x.s2) + x.s3) + x.s4) + x.s5) + x.s6) + x.s7);
  }

  /* Corner c has t = c >> 2, u = (c >> 1) & 1, v = c & 1: across t the pairs are
   * (c, c + 4), across u (c, c + 2) for c = 0, 1, 4, 5, across v (c, c + 1) for even c. */
  spread[0] = spread[1] = spread[2] = 0;
  for (int k = 0; k < 3; ++k) {
    const real8 x = value[k];
    spread[0] = fmax(spread[0], cs_most4(fabs(x.s4567 - x.s0123)));
    spread[1] = fmax(spread[1], cs_most4(fabs(x.s2367 - x.s0145)));
    spread[2] = fmax(spread[2], cs_most4(fabs(x.odd - x.even)));
  }

  /* Any direction d separates rigorously when d.F is bounded away from zero at every
   * corner. The guesses are F at the centre and the normal, (C + t D) x (E + t G) at the
   * middle time. */
  const real tm = (real)0.5 * (b.t0 + b.t1);
  real e1[3], e2[3], n[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = f->c[2][k] + tm * f->c[3][k];
    e2[k] = f->c[4][k] + tm * f->c[5][k];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  for (int which = 0; which < 2; ++which)
    if (cs_direction_separates(which ? n[0] : centre[0], which ? n[1] : centre[1], which ? n[2] : centre[2], value,
                               error, separation))
      return 0;
  return 1;
}

/* F at the corners of b, corner c (t = c >> 2, u = (c >> 1) & 1, v = c & 1) in
 * component c, and its error bound (cs_trilinear_at). */
inline void cs_trilinear_corners(const cs_trilinear* f, const cs_box b, real8 value[3], real8 error[3])
{
  const real8 t = (real8)(b.t0, b.t0, b.t0, b.t0, b.t1, b.t1, b.t1, b.t1);
  const real8 u = (real8)(b.u0, b.u0, b.u1, b.u1, b.u0, b.u0, b.u1, b.u1);
  const real8 v = (real8)(b.v0, b.v1, b.v0, b.v1, b.v0, b.v1, b.v0, b.v1);
  const real8 tu = t * u, tv = t * v;
  for (int k = 0; k < 3; ++k) {
    value[k] = CS_TRILINEAR_SUM(f->c, k, t, u, tu, v, tv);
    error[k] = CS_TRILINEAR_ERROR(CS_TRILINEAR_SUM(f->w, k, t, u, tu, v, tv));
  }
}

/* Coordinate k of CS_TRILINEAR_SUM's ((((a + t b) + u c) + t u d) + v e) + t v g with
 * (a, ..., g) = x[0..5][k], at the corners of the whole parameter box. There t, u and v
 * are 0 or 1: every product is exact and a term that is zero adds nothing, so these
 * sums, in the same order without those terms, are the same to the bit, for a fifth of
 * the arithmetic: partial sums are shared between corners. */
inline real8 cs_root_corner_sums(const real x[6][3], const int k)
{
  const real t0 = x[0][k], t1 = t0 + x[1][k];
  const real t0u1 = t0 + x[2][k], t1u1 = (t1 + x[2][k]) + x[3][k];
  return (real8)(t0, t0 + x[4][k], t0u1, t0u1 + x[4][k], t1, (t1 + x[4][k]) + x[5][k], t1u1,
                 (t1u1 + x[4][k]) + x[5][k]);
}

/* cs_trilinear_corners at the corners of the whole parameter box. */
inline void cs_trilinear_root_corners(const cs_trilinear* f, real8 value[3], real8 error[3])
{
  for (int k = 0; k < 3; ++k) {
    value[k] = cs_root_corner_sums(f->c, k);
    error[k] = CS_TRILINEAR_ERROR(cs_root_corner_sums(f->w, k));
  }
}

/* cs_trilinear_bounds_of, F evaluated at b's corners. */
inline int cs_trilinear_bounds(const cs_trilinear* f, const cs_box b, const real separation, real* width,
                               real* farthest, real nearest[2], real* first, real spread[3])
{
  real8 value[3], error[3];
  cs_trilinear_corners(f, b, value, error);
  return cs_trilinear_bounds_of(f, b, value, error, separation, width, farthest, nearest, first, spread);
}

/* cs_trilinear_bounds over the whole parameter box (the conservative screen). */
inline int cs_trilinear_root_bounds(const cs_trilinear* f, const real separation, real* width, real* farthest,
                                    real nearest[2], real* first, real spread[3])
{
  real8 value[3], error[3];
  cs_trilinear_root_corners(f, value, error);
  return cs_trilinear_bounds_of(f, cs_root_box(), value, error, separation, width, farthest, nearest, first,
                                spread);
}

#endif
