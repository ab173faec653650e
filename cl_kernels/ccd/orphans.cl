/* The cull of a scene's orphan pairs: the feature pairs of adjacent triangles, which the
 * decomposition never meets (topology.hpp), fixed for the scene and tested every step
 * by their swept bounds (bounds.h). The pairs whose boxes overlap are emitted in any
 * order: the tests they feed emit their contacts in any order too, so an
 * order-preserving compaction of the flags (a scan and a scatter) would cost two
 * launches a cull for nothing. */
#include "runtime/registration.h"
#include "bounds.h"

/* An edge's box is made where it is read: only the orphan pairs read edges' boxes since
 * the decomposition stopped (broad_phase.cl), and boxes kept for every edge held 72
 * bytes an edge (cloth-ball 9.5 MiB) and took a third of the swept bounds' work. */
inline void cs_edge_dop(__global const float* x0, __global const float* x1, __global const uint* edges,
                        const uint e, const float separation, float box[CS_DOP_FLOATS])
{
  const uint vertices[2] = {edges[2 * e], edges[2 * e + 1]};
  cs_swept_dop(x0, x1, vertices, 2, separation, box);
}

__kernel void cs_cull_edge_pairs(__global const uint2* pairs, const uint n, __global const float* x0,
                                 __global const float* x1, __global const uint* edges, const float separation,
                                 CS_EMITTER_PARAMS(uint2, kept))
{
  CS_EMITTER_BEGIN(kept);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 pair = pairs[i];
    float a[CS_DOP_FLOATS], b[CS_DOP_FLOATS];
    cs_edge_dop(x0, x1, edges, pair.x, separation, a);
    cs_edge_dop(x0, x1, edges, pair.y, separation, b);
    if (!cs_dops_apart(a, b)) CS_EMIT(kept, pair);
  }
  CS_EMITTER_END(kept);
}

/* A face's box is its BVH leaf's. */
__kernel void cs_cull_vertex_face_pairs(__global const uint2* pairs, const uint n, __global const float* x0,
                                        __global const float* x1, const float separation,
                                        __global const uint* face_words, __global const float* node_boxes,
                                        CS_EMITTER_PARAMS(uint2, kept))
{
  CS_EMITTER_BEGIN(kept);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 pair = pairs[i];
    float x[CS_DOP_FLOATS];
    cs_vertex_dop(x0, x1, pair.x, separation, x);
    if (!cs_dop_apart(x, node_boxes + CS_DOP_FLOATS * cs_face_leaf(face_words[pair.y]))) CS_EMIT(kept, pair);
  }
  CS_EMITTER_END(kept);
}
