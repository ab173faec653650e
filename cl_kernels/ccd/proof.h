#ifndef CSTREAMS_CCD_PROOF_H
#define CSTREAMS_CCD_PROOF_H
/* Proof that the contact function has an exact zero in a box: a contact that no
 * rounding of the inputs can undo.
 *
 * A float enclosure cannot tell a contact from a near miss closer than its own
 * rounding (a few ulps of the coordinates): both are "within the tolerance", and the
 * exact input may miss. A single-precision refinement therefore sends the contacts it
 * cannot prove here to a second look in double (refine.cl, CS_ESCALATE).
 *
 * Poincare-Miranda: where G = M F for a constant invertible M, and each G_i keeps one
 * sign on the box's face at the low end of parameter i and the opposite sign on the
 * face at its high end, G, and so F, vanishes in the box. M is the adjugate of F's
 * Jacobian at the box's centre (the inverse up to a factor), so that near a regular
 * zero G_i varies along parameter i alone. G is trilinear, as F is: over a face it
 * lies in the hull of the face's corner values, so the corners with their error
 * bounds decide. A tangent or parallel contact (a singular Jacobian) is not proven. */
#include "trilinear.h"

/* Whether G_i = m . F keeps opposite signs over the box's faces at the low and the
 * high end of parameter i, from F's values and error bounds at the corners (the margin
 * as cs_direction_separates takes it). */
inline int cs_miranda_row(const real m[3], const int i, const real8 value[3], const real8 error[3])
{
  const real a0 = fabs(m[0]), a1 = fabs(m[1]), a2 = fabs(m[2]);
  const real8 g = m[0] * value[0] + m[1] * value[1] + m[2] * value[2];
  const real8 margin = (a0 * (error[0] + (real)2 * CS_EPS * fabs(value[0])) +
                        a1 * (error[1] + (real)2 * CS_EPS * fabs(value[1])) +
                        a2 * (error[2] + (real)2 * CS_EPS * fabs(value[2]))) *
                           ((real)1 + (real)8 * CS_EPS) +
                       (real)8 * CS_TINY;
  const real8 lo = g - margin, hi = g + margin;
  /* Corner c has t = c >> 2, u = (c >> 1) & 1, v = c & 1 (cs_trilinear_corners). */
  const real4 low_lo = i == 0 ? lo.s0123 : i == 1 ? lo.s0145 : lo.even;
  const real4 low_hi = i == 0 ? hi.s0123 : i == 1 ? hi.s0145 : hi.even;
  const real4 high_lo = i == 0 ? lo.s4567 : i == 1 ? lo.s2367 : lo.odd;
  const real4 high_hi = i == 0 ? hi.s4567 : i == 1 ? hi.s2367 : hi.odd;
  /* Each end one step out: the additions above rounded to nearest. */
  const int rising = cs_up(cs_most4(low_hi)) < 0 && cs_down(cs_least4(high_lo)) > 0;
  const int falling = cs_down(cs_least4(low_lo)) > 0 && cs_up(cs_most4(high_hi)) < 0;
  return rising || falling;
}

/* Whether F certainly vanishes in the box b (for a vertex-face query, within the
 * triangle: the box must lie in u + v <= 1). */
inline int cs_zero_proven(const cs_trilinear* f, const cs_box b, const int vertex_face)
{
  if (vertex_face && !(b.u1 + b.v1 <= 1)) return 0;
  const real at[3] = {(real)0.5 * (b.t0 + b.t1), (real)0.5 * (b.u0 + b.u1), (real)0.5 * (b.v0 + b.v1)};
  real j[3][3]; /* j[k][p]: dF_k / d parameter p */
  for (int k = 0; k < 3; ++k) cs_trilinear_slopes(f, k, at, j[k]);
  /* Row p of the adjugate: the cross product of the Jacobian's other two columns. */
  real m[3][3];
  for (int p = 0; p < 3; ++p) {
    const int q = (p + 1) % 3, r = (p + 2) % 3;
    m[p][0] = j[1][q] * j[2][r] - j[2][q] * j[1][r];
    m[p][1] = j[2][q] * j[0][r] - j[0][q] * j[2][r];
    m[p][2] = j[0][q] * j[1][r] - j[1][q] * j[0][r];
    /* Scaled to a largest entry of 1: any row is as valid, and tiny products would
     * otherwise fall into subnormals. */
    const real largest = fmax(fabs(m[p][0]), fmax(fabs(m[p][1]), fabs(m[p][2])));
    if (!(largest > CS_TINY * (real)0x1p24) || !isfinite(largest)) return 0;
    for (int k = 0; k < 3; ++k) m[p][k] /= largest;
  }
  /* M must be invertible, as computed: its determinant clear of its rounding. */
  const real c0 = m[1][1] * m[2][2] - m[1][2] * m[2][1], c1 = m[1][2] * m[2][0] - m[1][0] * m[2][2],
             c2 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const real det = m[0][0] * c0 + m[0][1] * c1 + m[0][2] * c2;
  const real size = fabs(m[0][0]) * (fabs(m[1][1] * m[2][2]) + fabs(m[1][2] * m[2][1])) +
                    fabs(m[0][1]) * (fabs(m[1][2] * m[2][0]) + fabs(m[1][0] * m[2][2])) +
                    fabs(m[0][2]) * (fabs(m[1][0] * m[2][1]) + fabs(m[1][1] * m[2][0]));
  if (!(fabs(det) > (real)16 * CS_EPS * size + (real)64 * CS_TINY)) return 0;
  real8 value[3], error[3];
  cs_trilinear_corners(f, b, value, error);
  for (int p = 0; p < 3; ++p)
    if (!cs_miranda_row(m[p], p, value, error)) return 0;
  return 1;
}

/* The box in which a hit's contact is sought: b grown by its own width on each side
 * within the parameter box, as the zero a hit box closes in on may lie just beside
 * it; b itself where the grown box would leave a vertex-face query's triangle. */
inline cs_box cs_proof_box(const cs_box b, const int vertex_face)
{
  cs_box g = b;
  g.t0 = fmax((real)0, b.t0 - (b.t1 - b.t0));
  g.t1 = fmin((real)1, b.t1 + (b.t1 - b.t0));
  g.u0 = fmax((real)0, b.u0 - (b.u1 - b.u0));
  g.u1 = fmin((real)1, b.u1 + (b.u1 - b.u0));
  g.v0 = fmax((real)0, b.v0 - (b.v1 - b.v0));
  g.v1 = fmin((real)1, b.v1 + (b.v1 - b.v0));
  return vertex_face && !(g.u1 + g.v1 <= 1) ? b : g;
}

#endif
