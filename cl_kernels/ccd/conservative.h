#ifndef CSTREAMS_CCD_CONSERVATIVE_H
#define CSTREAMS_CCD_CONSERVATIVE_H
/* The conservative solver: never a false negative.
 *
 * The contact function F(t, u, v) is bounded over boxes of parameters by bounds that
 * hold for the exact inputs (trilinear.h). A box is dropped when the bounds keep F
 * away from zero along the coordinate axes, along F at the box centre, or along the
 * face (or edge pair) normal; it is a contact when they keep every coordinate of F
 * within the tolerance of zero, when F vanishes at its first corner to within 2^-10
 * of the tolerance, or within the minimum separation everywhere (every point of it is
 * then a contact) or at a corner at its start time (a contact right at its start), or
 * at a corner at its end time when it is no longer than the tolerance in time;
 * otherwise it is narrowed to where F can still vanish (contract.h) and, unless that
 * took more than half of some parameter's range, halved along the parameter F varies
 * most with. Boxes that start after the earliest contact found are pruned. The
 * tolerance also bounds the time: boxes starting less than `tolerance` before the
 * earliest contact are not refined, and the answer is then moved `tolerance` earlier,
 * so it stays a lower bound of the first contact. Running out of work answers
 * "collision" at the earliest time any unexplored box could hold one.
 *
 * cs_visit_box holds the rules of one box; refine.cl runs the search, breadth first
 * across the device. */
#include "contract.h"

/* What the search does with one box. */
#define CS_BOX_DROP 0  /* excluded, or pruned by the earliest contact */
#define CS_BOX_HIT 1   /* a contact at its start (*hit) */
#define CS_BOX_SPLIT 2 /* refined: the halves are *lo and *hi, the earlier one (for t) *lo */
#define CS_BOX_NARROW 3 /* refined: narrowed to *lo alone (contract.h) */
#define CS_BOX_CUT 4   /* refined: *lo cut into the pieces of *cuts (cs_piece) */

#define CS_NARROWING_PASSES 4

/* Several halvings of a box at once: their count in the low 3 bits, then 2 bits a
 * halving for the parameter it halves (0 t, 1 u, 2 v), into 2^count pieces. */
typedef uint cs_cuts;

inline uint cs_pieces(const cs_cuts cuts) { return 1u << (cuts & 7u); }

/* Halves b along parameter j: the upper half where `upper`, else the lower one. Both
 * write to copies: Mesa's rusticl let a callee's writes to a struct passed by value
 * reach the caller's (the second piece of a box came out cut from the first). */
inline cs_box cs_half(const cs_box b, const uint j, const int upper)
{
  cs_box r = b;
  if (j == 0) {
    const real mid = (real)0.5 * (b.t0 + b.t1);
    if (upper) r.t0 = mid;
    else r.t1 = mid;
  } else if (j == 1) {
    const real mid = (real)0.5 * (b.u0 + b.u1);
    if (upper) r.u0 = mid;
    else r.u1 = mid;
  } else {
    const real mid = (real)0.5 * (b.v0 + b.v1);
    if (upper) r.v0 = mid;
    else r.v1 = mid;
  }
  return r;
}

/* Piece p of b: what halving it as `cuts` says, taking the upper half at halving l
 * where bit (count - 1 - l) of p is set, gives. Piece 0 starts earliest. */
inline cs_box cs_piece(const cs_box b, const cs_cuts cuts, const uint p)
{
  const uint count = cuts & 7u;
  cs_box r = b;
  for (uint l = 0; l < count; ++l) r = cs_half(r, (cuts >> (3 + 2 * l)) & 3u, (p >> (count - 1 - l)) & 1u);
  return r;
}

/* `levels` halvings (at most 7), each along the parameter F varies most with once the
 * ones before are made (a halving halves the spread along its parameter), or 0 where
 * some piece could be too short to halve: a parameter halved c times must span more
 * than 2^(c + 2) CS_EPS (parameters are at most 1), so that every midpoint falls
 * strictly inside its piece. */
inline cs_cuts cs_plan_cuts(const cs_box b, const real spread_of_b[3], const int levels)
{
  real spread[3] = {spread_of_b[0], spread_of_b[1], spread_of_b[2]};
  uint along[3] = {0, 0, 0};
  cs_cuts cuts = (uint)levels;
  for (int l = 0; l < levels; ++l) {
    const int j = cs_most_varied(spread);
    cuts |= (uint)j << (3 + 2 * l);
    ++along[j];
    spread[j] *= (real)0.5;
  }
  const real span[3] = {b.t1 - b.t0, b.u1 - b.u0, b.v1 - b.v0};
  for (int j = 0; j < 3; ++j)
    if (along[j] && !(span[j] > ldexp((real)CS_EPS, (int)along[j] + 2))) return 0;
  return cuts;
}

/* Whether b is under half of a along some parameter. */
inline int cs_box_halved(const cs_box a, const cs_box b)
{
  return b.t1 - b.t0 < (real)0.5 * (a.t1 - a.t0) || b.u1 - b.u0 < (real)0.5 * (a.u1 - a.u0) ||
         b.v1 - b.v0 < (real)0.5 * (a.v1 - a.v0);
}

/* best: the earliest contact so far (2 for none). out_of_work: the query's work limit
 * is reached, so a box that is not dropped is a contact (*limited set). *slack is set
 * when the tolerance cut the search short. A box to refine is halved once (*lo, *hi),
 * or with levels > 1 cut into 2^levels pieces of *lo where they are not too short. */
inline int cs_visit_box(const cs_trilinear* f, cs_box b, const int vertex_face, const real tol, const real tolerance,
                        const real separation, const real best, const int out_of_work, const int levels, int* slack,
                        int* limited, real* hit, cs_box* lo, cs_box* hi, cs_cuts* cuts)
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
  real width, farthest, nearest[2], first, spread[3];
  if (!cs_trilinear_bounds(f, b, separation, &width, &farthest, nearest, &first, spread)) return CS_BOX_DROP;
  *hit = b.t0;
  /* Every point of the box is then within the tolerance of touching. The bounds' width
   * within the tolerance (they hold zero) says so too but asks more: a box of
   * near-tangent features stays about twice its rounding error wide, in single
   * precision over the tolerance, and halving took rounds to bring such boxes under it
   * (H100, refinement ms: armadillo-rollers 0.63 -> 0.55, rod-twist 0.48 -> 0.39). */
  if (farthest <= tol) return CS_BOX_HIT;
  /* A contact at its first corner, where F vanishes to within 2^-10 of the
   * tolerance: features that touch exactly there (a vertex on a vertex it duplicates, a
   * point of one edge on the other) would otherwise be closed in on by halving, a round
   * a halving, until a box around the corner fits within the tolerance. */
  if (first <= tol * (real)0x1p-10) return CS_BOX_HIT;
  if (separation > 0) {
    /* |F_k| under separation / sqrt(3) for every k keeps |F| under separation. */
    const real within = separation * (real)0.57735;
    if (farthest < within || nearest[0] < within || (nearest[1] < within && b.t1 - b.t0 <= tolerance))
      return CS_BOX_HIT;
  }
  if (out_of_work) {
    *limited = 1;
    return CS_BOX_HIT;
  }
  /* Narrowing again while it more than halves the box along some parameter: near a
   * root each pass squares the box's size, for a fraction of a round's cost. Where F
   * spans no more than a few separations over the box, the region within the
   * separation is about as thick as the box, and narrowing only costs: pairs that
   * hover at the separation are tiled by halving. */
  const cs_box whole = b;
  const int passes = width > (real)4 * separation ? CS_NARROWING_PASSES : 0;
  for (int pass = 0; pass < passes; ++pass) {
    const cs_box before = b;
    if (!cs_trilinear_contract(f, &b, separation)) return CS_BOX_DROP;
    if (!cs_box_halved(before, b)) break;
  }
  *lo = b;
  if (cs_box_halved(whole, b)) return CS_BOX_NARROW; /* as far along as a halving, with no second box */
  if (levels > 1 && (*cuts = cs_plan_cuts(b, spread, levels)) != 0) return CS_BOX_CUT;
  const int axis = cs_most_varied(spread);
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

/* The answer from the earliest contact found and whether the tolerance cut in. */
inline real cs_final_time(real best, const int slack, const real tolerance)
{
  if (slack) best = fmax((real)0, cs_down(best - tolerance));
  return best <= 1 ? best : 1;
}

#endif
