/* Swept bounds of features over a step, and the level-by-level refit of the
 * BVH (nodes in breadth-first order: a level's nodes are contiguous and their
 * children lie in the next level). */
#include "bounds.h"
#include "runtime/common.h"

inline void cs_swept_dop(__global const float* x0, __global const float* x1, const uint* vertices, const int count,
                         const float separation, __global float* out)
{
  float lo[9], hi[9];
  cs_dop_empty(lo, hi);
  for (int i = 0; i < count; ++i) {
    const uint v = vertices[i];
    cs_dop_add(lo, hi, x0[3 * v], x0[3 * v + 1], x0[3 * v + 2]);
    cs_dop_add(lo, hi, x1[3 * v], x1[3 * v + 1], x1[3 * v + 2]);
  }
  cs_dop_inflate(lo, hi, separation);
  for (int k = 0; k < 9; ++k) {
    out[k] = lo[k];
    out[9 + k] = hi[k];
  }
}

/* One work-item per moving primitive: the nf faces, then the ne edges, then the nv
 * vertices, in one launch rather than one a kind. */
__kernel void cs_primitive_bounds(__global const float* x0, __global const float* x1, __global const uint* faces,
                                  __global const uint* edges, const uint nf, const uint ne, const uint nv,
                                  const float separation, __global float* face_boxes, __global float* edge_boxes,
                                  __global float* vertex_boxes)
{
  uint i = get_global_id(0);
  uint vertices[3];
  if (i < nf) {
    for (int c = 0; c < 3; ++c) vertices[c] = faces[3 * i + c];
    cs_swept_dop(x0, x1, vertices, 3, separation, face_boxes + (size_t)CS_DOP_FLOATS * i);
    return;
  }
  i -= nf;
  if (i < ne) {
    for (int c = 0; c < 2; ++c) vertices[c] = edges[2 * i + c];
    cs_swept_dop(x0, x1, vertices, 2, separation, edge_boxes + (size_t)CS_DOP_FLOATS * i);
    return;
  }
  i -= ne;
  if (i < nv) {
    vertices[0] = i;
    cs_swept_dop(x0, x1, vertices, 1, separation, vertex_boxes + (size_t)CS_DOP_FLOATS * i);
  }
}

/* nodes: (first child or -1, face or -1, parent, depth) per node. */
inline void cs_refit_node(__global const int4* nodes, __global const float* face_boxes, const uint node,
                          __global float* node_boxes)
{
  const int left = nodes[node].x, face = nodes[node].y;
  __global float* out = node_boxes + (size_t)CS_DOP_FLOATS * node;
  if (left < 0) {
    for (int k = 0; k < CS_DOP_FLOATS; ++k) out[k] = face_boxes[(size_t)CS_DOP_FLOATS * face + k];
    return;
  }
  __global const float* a = node_boxes + (size_t)CS_DOP_FLOATS * left;
  __global const float* b = a + CS_DOP_FLOATS;
  for (int k = 0; k < 9; ++k) {
    out[k] = fmin(a[k], b[k]);
    out[9 + k] = fmax(a[9 + k], b[9 + k]);
  }
}

__kernel void cs_refit_level(__global const int4* nodes, __global const float* face_boxes, const uint first,
                             const uint count, __global float* node_boxes)
{
  const uint i = get_global_id(0);
  if (i < count) cs_refit_node(nodes, face_boxes, first + i, node_boxes);
}

/* Levels `top` up to 0, deepest first, by one work-group: each of these levels holds
 * too few nodes to be worth a launch of its own (a launch costs about as much as
 * refitting a few hundred nodes). The barrier makes a level's boxes visible to the
 * group before the level above reads them. levels: as SceneLayout::levels. */
CS_GROUP_KERNEL void cs_refit_top_levels(__global const int4* nodes, __global const float* face_boxes,
                                         __global const uint* levels, const uint top, __global float* node_boxes)
{
  for (uint level = top + 1; level-- > 0;) {
    const uint end = levels[level + 1];
    for (uint node = levels[level] + get_local_id(0); node < end; node += CS_WG_SIZE)
      cs_refit_node(nodes, face_boxes, node, node_boxes);
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
}
