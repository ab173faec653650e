#ifndef CSTREAMS_CCD_FILTER_H
#define CSTREAMS_CCD_FILTER_H
/* Deforming non-penetration filter (Tang, Curtis, Yoon, Manocha 2010). Any contact of
 * a vertex with a face, or of two edges, happens when the four points are coplanar,
 * i.e. at a root of the cubic f(t) = ((x1 - x0) x (x2 - x0)) . (x3 - x0) (vertex-face:
 * x0..x2 the face, x3 the vertex; edge-edge: (a1 - a0) x (b0 - a0) . (b1 - a0)). If
 * f's four Bernstein coefficients over [0, 1] share a strict sign, f has no root there
 * and the pair cannot collide. Coefficients are computed in interval arithmetic, so a
 * pair is culled only when that is certain. Contacts at a distance (minimum
 * separation) need no coplanarity, so the filter is not used then. */
#include "query.h"

/* Linear motion of x_b - x_a: start and velocity as intervals per coordinate. */
inline void cs_relative(const cs_query* q, int a, int b, cs_interval start[3], cs_interval velocity[3])
{
  for (int k = 0; k < 3; ++k) {
    start[k] = cs_isub(q->x[b][k], q->x[a][k]);
    velocity[k] = cs_isub(cs_isub(q->x[b + 4][k], q->x[a + 4][k]), start[k]);
  }
}

inline void cs_cross(const cs_interval a[3], const cs_interval b[3], cs_interval out[3])
{
  out[0] = cs_isub(cs_imul(a[1], b[2]), cs_imul(a[2], b[1]));
  out[1] = cs_isub(cs_imul(a[2], b[0]), cs_imul(a[0], b[2]));
  out[2] = cs_isub(cs_imul(a[0], b[1]), cs_imul(a[1], b[0]));
}

inline cs_interval cs_dot(const cs_interval a[3], const cs_interval b[3])
{
  return cs_iadd(cs_iadd(cs_imul(a[0], b[0]), cs_imul(a[1], b[1])), cs_imul(a[2], b[2]));
}

/* f's coefficients, k[0] + k[1] t + k[2] t^2 + k[3] t^3, each an interval that holds
 * for the exact inputs. */
inline void cs_coplanarity_cubic(const cs_query* q, const int vertex_face, cs_interval k[4])
{
  /* A = x1 - x0, B = x2 - x0, C = x3 - x0, each A0 + t Av. */
  cs_interval A0[3], Av[3], B0[3], Bv[3], C0[3], Cv[3];
  if (vertex_face) { /* points: 0 vertex, 1..3 face: f = ((f1-f0) x (f2-f0)) . (p - f0) */
    cs_relative(q, 1, 2, A0, Av);
    cs_relative(q, 1, 3, B0, Bv);
    cs_relative(q, 1, 0, C0, Cv);
  } else {          /* 0,1 edge a; 2,3 edge b: f = ((a1-a0) x (b0-a0)) . (b1-a0) */
    cs_relative(q, 0, 1, A0, Av);
    cs_relative(q, 0, 2, B0, Bv);
    cs_relative(q, 0, 3, C0, Cv);
  }
  cs_interval n0[3], n1a[3], n1b[3], n1[3], n2[3];
  cs_cross(A0, B0, n0);
  cs_cross(A0, Bv, n1a);
  cs_cross(Av, B0, n1b);
  for (int j = 0; j < 3; ++j) n1[j] = cs_iadd(n1a[j], n1b[j]);
  cs_cross(Av, Bv, n2);
  k[0] = cs_dot(n0, C0);
  k[1] = cs_iadd(cs_dot(n0, Cv), cs_dot(n1, C0));
  k[2] = cs_iadd(cs_dot(n1, Cv), cs_dot(n2, C0));
  k[3] = cs_dot(n2, Cv);
}

/* Returns 1 when the cubic with coefficients k certainly has no root in [0, 1]. */
inline int cs_cubic_keeps_sign(const cs_interval k[4])
{
  /* Bernstein coefficients times 3 (same signs): 3k0, 3k0 + k1, 3k0 + 2k1 + k2, 3(k0+k1+k2+k3). */
  const cs_interval b0 = k[0];
  const cs_interval b1 = cs_iadd(cs_iscale(k[0], 3), k[1]);
  const cs_interval b2 = cs_iadd(cs_iadd(cs_iscale(k[0], 3), cs_iscale(k[1], 2)), k[2]);
  const cs_interval b3 = cs_iadd(cs_iadd(k[0], k[1]), cs_iadd(k[2], k[3]));
  const int positive = b0.lo > 0 && b1.lo > 0 && b2.lo > 0 && b3.lo > 0;
  const int negative = b0.hi < 0 && b1.hi < 0 && b2.hi < 0 && b3.hi < 0;
  return positive || negative;
}

/* Returns 1 when the pair certainly has no coplanarity in [0, 1]. */
inline int cs_non_penetration_filter(const cs_query* q, const int vertex_face)
{
  cs_interval k[4];
  cs_coplanarity_cubic(q, vertex_face, k);
  return cs_cubic_keeps_sign(k);
}

#endif
