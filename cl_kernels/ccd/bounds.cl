/* Swept bounds of features over a step, and the refit of the BVH, bottom up (nodes in
 * breadth-first order: a level's nodes are contiguous and their children lie in the
 * next level). */
#include "bounds.h"
#include "runtime/common.h"

/* One work-item per moving face or edge (the nf faces, then the ne edges), in one
 * launch rather than one a kind; a vertex's box is made where it is read (bounds.h).
 * The group's boxes are staged in local memory and written word by word across the
 * group, neighbouring work-items to neighbouring words: a box a work-item put 72 bytes
 * between the words of one store. A face's box is its BVH leaf's (cs_face_leaf of its
 * word), which the refit then leaves as it is: kept apart as well, the faces' boxes held
 * n-body's 10 MiB twice. */
CS_GROUP_KERNEL void cs_primitive_bounds(__global const float* x0, __global const float* x1,
                                         __global const uint* faces, __global const uint* edges, const uint nf,
                                         const uint ne, const float separation,
                                         __global const uint* face_words, __global float* node_boxes,
                                         __global float* edge_boxes)
{
  __local float staged[CS_WG_SIZE * CS_DOP_FLOATS];
  const uint lid = get_local_id(0), first = get_group_id(0) * CS_WG_SIZE, i = first + lid;
  const uint total = nf + ne;
  uint vertices[3];
  int count = 0;
  if (i < nf) {
    for (int c = 0; c < 3; ++c) vertices[c] = faces[3 * i + c];
    count = 3;
  } else if (i < total) {
    for (int c = 0; c < 2; ++c) vertices[c] = edges[2 * (i - nf) + c];
    count = 2;
  }
  if (count) {
    float box[CS_DOP_FLOATS];
    cs_swept_dop(x0, x1, vertices, count, separation, box);
    for (int k = 0; k < CS_DOP_FLOATS; ++k) staged[CS_DOP_FLOATS * lid + k] = box[k];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint words = min((uint)CS_WG_SIZE, total - first) * CS_DOP_FLOATS;
  for (uint w = lid; w < words; w += CS_WG_SIZE) {
    const uint j = first + w / CS_DOP_FLOATS, k = w % CS_DOP_FLOATS;
    __global float* box = j < nf ? node_boxes + (size_t)CS_DOP_FLOATS * cs_face_leaf(face_words[j])
                                 : edge_boxes + (size_t)CS_DOP_FLOATS * (j - nf);
    box[k] = staged[w];
  }
}

/* nodes: packed (bounds.h). A leaf holds its face's box already (cs_primitive_bounds). */
inline void cs_refit_node(__global const int2* nodes, const uint node, __global float* node_boxes)
{
  const int left = nodes[node].x;
  if (left < 0) return;
  float a[CS_DOP_FLOATS], b[CS_DOP_FLOATS];
  cs_dop_load(node_boxes + (size_t)CS_DOP_FLOATS * left, a);
  cs_dop_load(node_boxes + (size_t)CS_DOP_FLOATS * (left + 1), b);
  for (int k = 0; k < 9; ++k) {
    a[k] = fmin(a[k], b[k]);
    a[9 + k] = fmax(a[9 + k], b[9 + k]);
  }
  cs_dop_store(a, node_boxes + (size_t)CS_DOP_FLOATS * node);
}

/* Levels top to top + depth - 1 of the forest, deepest first, in one launch, one group
 * a node of level top; the level below them was refitted by the launch before. In
 * breadth-first order the children of consecutive nodes are consecutive, so what a
 * group refits at each level is one range of it: ranges[first + group * depth + d] for
 * level top + d (plan_refit, ccd_graph.cpp). A barrier makes a level's boxes visible to
 * the group before the level above reads them. A launch a level cost its launch and its
 * tail (H100, cloth-ball: 0.14 ms for 18 levels); a group's barrier costs far less. */
CS_GROUP_KERNEL void cs_refit_levels(__global const int2* nodes, __global const uint2* ranges, const uint first,
                                     const uint depth, __global float* node_boxes)
{
  ranges += first + (size_t)get_group_id(0) * depth;
  for (uint d = depth; d-- > 0;) {
    const uint2 r = ranges[d];
    for (uint n = r.x + get_local_id(0); n < r.y; n += CS_WG_SIZE) cs_refit_node(nodes, n, node_boxes);
    if (d) barrier(CLK_GLOBAL_MEM_FENCE);
  }
}
