/* Proximity: which candidate pairs of a configuration (a vertex and a face, or two
 * edges, from the broad phase run with the positions at both ends and the distance
 * dhat as its separation) lie closer than dhat, with their distance and its type:
 * which closest features, as ipc-toolkit names them (PointTriangleDistanceType,
 * EdgeEdgeDistanceType, in the same order).
 *
 * A pair's distance is the least of the distances between points of its two features
 * that the candidates below reach: the closest points found by the usual regions
 * (Ericson, Real-Time Collision Detection, 5.1.5 and 5.1.9), clamped onto the features,
 * and every pair of a point with the other feature's edges and vertices. Each is the
 * distance of two points on the features, so none is below the true distance by more
 * than rounding, and where the regions are ill-conditioned (a needle or a degenerate
 * triangle, nearly parallel edges) the boundary candidates hold the minimum within
 * rounding too. A pair is reported where that least distance is below dhat plus
 * CS_DISTANCE_ULPS units of rounding at the pair's scale, so that no pair closer than
 * dhat is missed. */
#include "pairs.h"
#include "real.h"
#include "runtime/registration.h"
#include "streams.h"

#define CS_DISTANCE_ULPS 16

/* Point-triangle types: the vertex t0, t1, t2; the edge t0t1, t1t2, t2t0; the face. */
#define CS_P_T0 0
#define CS_P_E0 3
#define CS_P_T 6
/* Edge-edge types: EAi_EBj a vertex of each; EA_EBj edge a and a vertex of b; EAi_EB a
 * vertex of a and edge b; EA_EB both edges. */
#define CS_EA0_EB0 0
#define CS_EA_EB0 4
#define CS_EA0_EB 6
#define CS_EA_EB 8

typedef struct {
  real x, y, z;
} cs_v3;

inline cs_v3 cs_load(__global const real* x, const uint v)
{
  cs_v3 r;
  r.x = x[3 * v];
  r.y = x[3 * v + 1];
  r.z = x[3 * v + 2];
  return r;
}
inline cs_v3 cs_sub(const cs_v3 a, const cs_v3 b)
{
  cs_v3 r;
  r.x = a.x - b.x;
  r.y = a.y - b.y;
  r.z = a.z - b.z;
  return r;
}
inline cs_v3 cs_along(const cs_v3 a, const cs_v3 d, const real s)
{
  cs_v3 r;
  r.x = a.x + s * d.x;
  r.y = a.y + s * d.y;
  r.z = a.z + s * d.z;
  return r;
}
inline real cs_dot(const cs_v3 a, const cs_v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline real cs_dist2(const cs_v3 a, const cs_v3 b)
{
  const cs_v3 d = cs_sub(a, b);
  return cs_dot(d, d);
}
inline real cs_magnitude(const cs_v3 a) { return fmax(fmax(fabs(a.x), fabs(a.y)), fabs(a.z)); }

/* The squared distance from p to the segment ab, its foot clamped onto the segment;
 * *at_end is 0 or 1 where the foot is that end, else -1. */
inline real cs_point_segment(const cs_v3 p, const cs_v3 a, const cs_v3 b, int* at_end)
{
  const cs_v3 d = cs_sub(b, a);
  const real len2 = cs_dot(d, d), along = cs_dot(cs_sub(p, a), d);
  real s = len2 > 0 ? along / len2 : 0;
  *at_end = s <= 0 ? 0 : (s >= 1 ? 1 : -1);
  s = clamp(s, (real)0, (real)1);
  return cs_dist2(p, cs_along(a, d, s));
}

/* Keeps the smaller of (*best, *type) and (d2, t). */
inline void cs_keep(real* best, int* type, const real d2, const int t)
{
  if (d2 < *best) {
    *best = d2;
    *type = t;
  }
}

/* The squared distance from p to the triangle t0 t1 t2 and its type. */
inline real cs_point_triangle(const cs_v3 p, const cs_v3 t[3], int* type)
{
  real best = CS_REAL_MAX;
  *type = CS_P_T;
  for (int k = 0; k < 3; ++k) {
    int end;
    const real d2 = cs_point_segment(p, t[k], t[(k + 1) % 3], &end);
    cs_keep(&best, type, d2, end < 0 ? CS_P_E0 + k : CS_P_T0 + (k + end) % 3);
  }
  /* The face's own closest point, by barycentric coordinates clamped into it: it is
   * the minimum where the foot of p falls inside, and never closer than the triangle. */
  const cs_v3 ab = cs_sub(t[1], t[0]), ac = cs_sub(t[2], t[0]), ap = cs_sub(p, t[0]);
  const real d00 = cs_dot(ab, ab), d01 = cs_dot(ab, ac), d11 = cs_dot(ac, ac);
  const real d20 = cs_dot(ap, ab), d21 = cs_dot(ap, ac), det = d00 * d11 - d01 * d01;
  if (det > 0) {
    real v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
    if (v > 0 && w > 0 && v + w < 1) {
      v = clamp(v, (real)0, (real)1);
      w = clamp(w, (real)0, (real)1 - v);
      const cs_v3 q = cs_along(cs_along(t[0], ab, v), ac, w);
      cs_keep(&best, type, cs_dist2(p, q), CS_P_T);
    }
  }
  return best;
}

/* The squared distance between the segments a0 a1 and b0 b1, and its type. */
inline real cs_edge_edge(const cs_v3 a0, const cs_v3 a1, const cs_v3 b0, const cs_v3 b1, int* type)
{
  real best = CS_REAL_MAX;
  *type = CS_EA_EB;
  const cs_v3 a[2] = {a0, a1}, b[2] = {b0, b1};
  for (int i = 0; i < 2; ++i) {
    int end;
    /* A vertex of a against edge b, then a vertex of b against edge a. */
    real d2 = cs_point_segment(a[i], b0, b1, &end);
    cs_keep(&best, type, d2, end < 0 ? CS_EA0_EB + i : CS_EA0_EB0 + 2 * i + end);
    d2 = cs_point_segment(b[i], a0, a1, &end);
    cs_keep(&best, type, d2, end < 0 ? CS_EA_EB0 + i : CS_EA0_EB0 + 2 * end + i);
  }
  const cs_v3 d1 = cs_sub(a1, a0), d2 = cs_sub(b1, b0), r = cs_sub(a0, b0);
  const real aa = cs_dot(d1, d1), bb = cs_dot(d1, d2), ee = cs_dot(d2, d2), c = cs_dot(d1, r), f = cs_dot(d2, r);
  const real det = aa * ee - bb * bb;
  if (det > 0) {
    const real s = (bb * f - c * ee) / det, t = (aa * f - bb * c) / det;
    if (s > 0 && s < 1 && t > 0 && t < 1) cs_keep(&best, type, cs_dist2(cs_along(a0, d1, s), cs_along(b0, d2, t)), CS_EA_EB);
  }
  return best;
}

CS_DEFINE_STREAM_ITEM(uint2)

/* One work-item a candidate pair; emits (kind << 31 | a, b, distance as a float rounded
 * to nearest, type) for each pair closer than dhat (within rounding), where kind is 0
 * for a vertex and a face (a the vertex, b the face) and 1 for two edges: sorted as
 * unsigned words, the first two put the pairs in canonical order (ids stay below
 * 2^31). */
__kernel void cs_close_pairs(CS_FOUR_STREAMS(uint2), __global const real* x, __global const uint* faces,
                             __global const uint* edges, const real dhat, CS_EMITTER_PARAMS(uint4, close))
{
  CS_EMITTER_BEGIN(close);
  uint2 pair;
  uint vertex_face;
  if (cs_stream_item_uint2(get_global_id(0), CS_FOUR_STREAM_ARGS, &pair, &vertex_face)) {
    uint v[4];
    cs_pair_vertices(pair, vertex_face, faces, edges, v);
    cs_v3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = cs_load(x, v[k]);
    real scale = 0;
    for (int k = 0; k < 4; ++k) scale = fmax(scale, cs_magnitude(p[k]));
    int type;
    const real d2 = vertex_face ? cs_point_triangle(p[0], p + 1, &type) : cs_edge_edge(p[0], p[1], p[2], p[3], &type);
    const real d = sqrt(d2), reach = dhat + CS_DISTANCE_ULPS * CS_EPS * scale;
    if (d < reach) CS_EMIT(close, (uint4)((vertex_face ? 0u : 1u << 31) | pair.x, pair.y, as_uint((float)d), (uint)type));
  }
  CS_EMITTER_END(close);
}
