/* The cull of a scene's orphan pairs: the feature pairs of adjacent triangles, which the
 * decomposition never meets (topology.hpp), fixed for the scene and tested every step
 * by their swept bounds (bounds.h). The pairs whose boxes overlap are emitted in any
 * order: the tests they feed emit their contacts in any order too, so an
 * order-preserving compaction of the flags (a scan and a scatter) would cost two
 * launches a cull for nothing. */
#include "runtime/registration.h"
#include "bounds.h"

__kernel void cs_cull_edge_pairs(__global const uint2* pairs, const uint n, __global const float* edge_boxes,
                                 CS_EMITTER_PARAMS(uint2, kept))
{
  CS_EMITTER_BEGIN(kept);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 pair = pairs[i];
    if (cs_dop_overlap(edge_boxes + CS_DOP_FLOATS * pair.x, edge_boxes + CS_DOP_FLOATS * pair.y)) CS_EMIT(kept, pair);
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
