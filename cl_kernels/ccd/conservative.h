#ifndef CSTREAMS_CCD_CONSERVATIVE_H
#define CSTREAMS_CCD_CONSERVATIVE_H
/* The conservative solver: never a false negative.
 *
 * The contact function F(t, u, v) (vertex-face: p - f0 - u (f1 - f0) - v (f2 - f0);
 * edge-edge: a0 + u (a1 - a0) - b0 - v (b1 - b0), every point moving linearly in t) is
 * multilinear, so over a box of (t, u, v) it lies in the hull of its eight corner
 * values. Corners are evaluated in interval arithmetic rounded outward, so the bounds
 * hold for the exact inputs. A box is dropped when the bounds keep F away from zero
 * along the coordinate axes, along F at the box centre, or along the face (or edge
 * pair) normal; it is a contact when they fit within the tolerance; otherwise it is
 * halved along the parameter F varies most with. Boxes that start after the earliest contact found are pruned. The tolerance
 * also bounds the time: boxes starting less than `tolerance` before the earliest
 * contact are not refined, and the answer is then moved `tolerance` earlier, so it
 * stays a lower bound of the first contact. Running out of work answers "collision"
 * at the earliest time any unexplored box could hold one.
 *
 * Two searches share the rules of one box (cs_visit_box): breadth first across a
 * work-group (refine.cl), where the earliest contact prunes only from one round to the
 * next, so the answer does not depend on scheduling; and depth first within one
 * work-item (cs_conservative), the fallback for queries too wide for a work-group. */
#include "query.h"

#ifndef CS_STACK_SIZE
#define CS_STACK_SIZE 64
#endif

typedef struct {
  real t0, t1, u0, u1, v0, v1;
} cs_box;

typedef struct {
  cs_interval start[4][3];
  cs_interval motion[4][3];
  int vertex_face;
} cs_contact_function;

inline cs_contact_function cs_make_contact_function(const cs_query* q, const int vertex_face)
{
  cs_contact_function f;
  f.vertex_face = vertex_face;
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      f.start[i][k] = q->x[i][k];
      f.motion[i][k] = cs_isub(q->x[i + 4][k], q->x[i][k]);
    }
  return f;
}

/* Bounds F over the box. Returns 0 when F certainly stays farther than `separation`
 * from zero there; otherwise sets *width to the widest side of the bounding box of F
 * and *split to the parameter (0 t, 1 u, 2 v) along which F varies most. */
inline int cs_box_bounds(const cs_contact_function* f, const cs_box b, const real separation, real* width, int* split)
{
  cs_interval corner[8][3];
  real mid[4][3];
  for (int it = 0; it < 2; ++it) {
    const real t = it ? b.t1 : b.t0;
    cs_interval x[4][3];
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) {
        x[i][k] = cs_iadd(f->start[i][k], cs_iscale(f->motion[i][k], t));
        mid[i][k] = it ? (real)0.5 * (mid[i][k] + x[i][k].lo) : x[i][k].lo;
      }
    for (int iu = 0; iu < 2; ++iu)
      for (int iv = 0; iv < 2; ++iv) {
        const real u = iu ? b.u1 : b.u0, v = iv ? b.v1 : b.v0;
        const int c = it * 4 + iu * 2 + iv;
        for (int k = 0; k < 3; ++k) {
          if (f->vertex_face) {
            const cs_interval e1 = cs_isub(x[2][k], x[1][k]), e2 = cs_isub(x[3][k], x[1][k]);
            corner[c][k] = cs_isub(cs_isub(cs_isub(x[0][k], x[1][k]), cs_iscale(e1, u)), cs_iscale(e2, v));
          } else {
            const cs_interval ea = cs_isub(x[1][k], x[0][k]), eb = cs_isub(x[3][k], x[2][k]);
            corner[c][k] = cs_isub(cs_isub(cs_iadd(x[0][k], cs_iscale(ea, u)), x[2][k]), cs_iscale(eb, v));
          }
        }
      }
  }

  real centre[3] = {0, 0, 0};
  *width = 0;
  for (int k = 0; k < 3; ++k) {
    real lo = CS_REAL_MAX, hi = -CS_REAL_MAX;
    for (int c = 0; c < 8; ++c) {
      lo = fmin(lo, corner[c][k].lo);
      hi = fmax(hi, corner[c][k].hi);
      centre[k] += (real)0.0625 * (corner[c][k].lo + corner[c][k].hi);
    }
    if (lo > separation || hi < -separation) return 0;
    *width = fmax(*width, hi - lo);
  }

  /* Corner c has t = c >> 2, u = (c >> 1) & 1, v = c & 1. */
  real spread[3] = {0, 0, 0};
  for (int c = 0; c < 8; ++c)
    for (int axis = 0; axis < 3; ++axis) {
      const int bit = 4 >> axis;
      if (c & bit) continue;
      for (int k = 0; k < 3; ++k) spread[axis] = fmax(spread[axis], fabs(corner[c | bit][k].lo - corner[c][k].lo));
    }
  *split = spread[0] >= spread[1] ? (spread[0] >= spread[2] ? 0 : 2) : (spread[1] >= spread[2] ? 1 : 2);

  /* Any direction separates rigorously when every corner's dot product with it is
   * bounded away from zero; the guesses are F at the centre and the normal. */
  real n[3];
  if (f->vertex_face) {
    const real e1[3] = {mid[2][0] - mid[1][0], mid[2][1] - mid[1][1], mid[2][2] - mid[1][2]};
    const real e2[3] = {mid[3][0] - mid[1][0], mid[3][1] - mid[1][1], mid[3][2] - mid[1][2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  } else {
    const real ea[3] = {mid[1][0] - mid[0][0], mid[1][1] - mid[0][1], mid[1][2] - mid[0][2]};
    const real eb[3] = {mid[3][0] - mid[2][0], mid[3][1] - mid[2][1], mid[3][2] - mid[2][2]};
    n[0] = ea[1] * eb[2] - ea[2] * eb[1];
    n[1] = ea[2] * eb[0] - ea[0] * eb[2];
    n[2] = ea[0] * eb[1] - ea[1] * eb[0];
  }
  for (int which = 0; which < 2; ++which) {
    real d0 = which ? n[0] : centre[0], d1 = which ? n[1] : centre[1], d2 = which ? n[2] : centre[2];
    /* Scaled to a largest component of 1: any direction is as valid, and products with
     * tiny directions would otherwise fall into subnormals (slow on CPUs). */
    const real largest = fmax(fabs(d0), fmax(fabs(d1), fabs(d2)));
    if (!(largest > CS_TINY * (real)0x1p24) || !isfinite(largest)) continue;
    d0 /= largest;
    d1 /= largest;
    d2 /= largest;
    const real norm1 = fabs(d0) + fabs(d1) + fabs(d2);
    real lo = CS_REAL_MAX, hi = -CS_REAL_MAX;
    for (int c = 0; c < 8; ++c) {
      const cs_interval dot =
          cs_iadd(cs_iadd(cs_iscale(corner[c][0], d0), cs_iscale(corner[c][1], d1)), cs_iscale(corner[c][2], d2));
      lo = fmin(lo, dot.lo);
      hi = fmax(hi, dot.hi);
    }
    const real reach = cs_up(separation * cs_up(norm1));
    if (lo > reach || hi < -reach) return 0;
  }
  return 1;
}

/* What the search does with one box. */
#define CS_BOX_DROP 0  /* excluded, or pruned by the earliest contact */
#define CS_BOX_HIT 1   /* a contact at its start (*hit) */
#define CS_BOX_SPLIT 2 /* refined: the halves are *lo and *hi, the earlier one (for t) *lo */

/* best: the earliest contact so far (2 for none). out_of_work: the query's work limit
 * is reached, so a box that is not dropped is a contact (*limited set). *slack is set
 * when the tolerance cut the search short. */
inline int cs_visit_box(const cs_contact_function* f, cs_box b, const int vertex_face, const real tol, const real tolerance,
                        const real separation, const real best, const int out_of_work, int* slack, int* limited,
                        real* hit, cs_box* lo, cs_box* hi)
{
  if (b.t0 >= best) return CS_BOX_DROP;
  if (b.t0 >= best - tolerance) {
    *slack = 1;
    return CS_BOX_DROP;
  }
  /* Only the part before best - tolerance can still matter; bounds hold for any box,
   * so the rest is cut off rather than refined point by point along a contact line. */
  if (b.t1 > best - tolerance) {
    b.t1 = best - tolerance;
    *slack = 1;
  }
  if (vertex_face && b.u0 + b.v0 > 1) return CS_BOX_DROP;
  real width;
  int axis;
  if (!cs_box_bounds(f, b, separation, &width, &axis)) return CS_BOX_DROP;
  *hit = b.t0;
  if (width <= tol) return CS_BOX_HIT;
  if (out_of_work) {
    *limited = 1;
    return CS_BOX_HIT;
  }
  *lo = b;
  *hi = b;
  if (axis == 0) {
    lo->t1 = hi->t0 = (real)0.5 * (b.t0 + b.t1);
  } else if (axis == 1) {
    lo->u1 = hi->u0 = (real)0.5 * (b.u0 + b.u1);
  } else {
    lo->v1 = hi->v0 = (real)0.5 * (b.v0 + b.v1);
  }
  const int cannot_halve = axis == 0 ? (lo->t1 == b.t0 || hi->t0 == b.t1)
                           : axis == 1 ? (lo->u1 == b.u0 || hi->u0 == b.u1)
                                       : (lo->v1 == b.v0 || hi->v0 == b.v1);
  return cannot_halve ? CS_BOX_HIT : CS_BOX_SPLIT; /* as fine as this precision goes: a contact */
}

inline real cs_query_scale(const cs_query* q)
{
  real s = CS_TINY;
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 3; ++k) s = fmax(s, fmax(fabs(q->x[i][k].lo), fabs(q->x[i][k].hi)));
  return s;
}

inline cs_box cs_root_box(void)
{
  const cs_box root = {0, 1, 0, 1, 0, 1};
  return root;
}

/* The answer from the earliest contact found and whether the tolerance cut in. */
inline real cs_final_time(real best, const int slack, const real tolerance)
{
  if (slack) best = fmax((real)0, cs_down(best - tolerance));
  return best <= 1 ? best : 1;
}

inline uint cs_conservative(const cs_query* q, const int vertex_face, const real tolerance, const real separation,
                            const uint max_iterations, real* toi)
{
  const cs_contact_function f = cs_make_contact_function(q, vertex_face);
  const real tol = tolerance * cs_query_scale(q);
  cs_box stack[CS_STACK_SIZE];
  int top = 0;
  stack[top++] = cs_root_box();
  real best = 2; /* no contact yet */
  int slack = 0;
  uint status = CS_SEPARATE;
  uint iterations = 0;
  while (top > 0) {
    const cs_box b = stack[--top];
    int limited = 0;
    real hit;
    cs_box lo, hi;
    const int visit = cs_visit_box(&f, b, vertex_face, tol, tolerance, separation, best, iterations >= max_iterations,
                                   &slack, &limited, &hit, &lo, &hi);
    if (visit == CS_BOX_DROP) continue;
    if (limited) {
      for (int i = 0; i < top; ++i) hit = fmin(hit, stack[i].t0);
      best = fmin(best, hit);
      status = CS_LIMIT;
      break;
    }
    if (visit == CS_BOX_HIT) {
      best = fmin(best, hit);
      if (status == CS_SEPARATE) status = CS_COLLIDES;
      continue;
    }
    ++iterations;
    if (top + 2 > CS_STACK_SIZE) {
      best = fmin(best, b.t0);
      status = CS_LIMIT;
      continue;
    }
    stack[top++] = hi;
    stack[top++] = lo; /* the earlier half (for t splits) is searched first */
  }
  *toi = cs_final_time(best, slack, tolerance);
  return status;
}

#endif
