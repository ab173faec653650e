/* Broad phase of one self-colliding mesh: BVTT traversal from a seed front of node
 * pairs to non-adjacent triangle pairs, their decomposition into vertex-face and
 * edge-edge pairs by feature ownership, and the cull of feature pairs (and of the
 * orphan pairs) by their swept bounds. Boxes are 18 floats (bounds.h). */
#include "runtime/registration.h"
#include "bounds.h"

/* Along a depth-first path from a seed, a node against itself pushes three pairs (net
 * +2) and descends both sides, a pair of nodes pushes two (net +1) and descends one
 * side, so the stack holds at most 2 * depth + 1 pairs: 128 covers trees of up to 40
 * levels, and the host refuses deeper ones. */
#define CS_BVTT_STACK 128

inline int cs_dop_overlap(__global const float* a, __global const float* b)
{
  for (int k = 0; k < 9; ++k)
    if (a[k] > b[9 + k] || b[k] > a[9 + k]) return 0;
  return 1;
}

inline int cs_faces_adjacent(__global const uint* faces, const uint f, const uint g)
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (faces[3 * f + i] == faces[3 * g + j]) return 1;
  return 0;
}

/* nodes: (left or -1, face or -1, parent); seeds: node pairs (i, j), i == j meaning the
 * node against itself. */
__kernel void cs_traverse(__global const int2* seeds, const uint n, __global const int* nodes,
                          __global const float* node_boxes, __global const uint* faces,
                          CS_EMITTER_PARAMS(uint2, pairs))
{
  CS_EMITTER_BEGIN(pairs);
  const uint s = get_global_id(0);
  if (s < n) {
    int2 stack[CS_BVTT_STACK];
    int top = 0;
    stack[top++] = seeds[s];
    while (top > 0) {
      const int2 p = stack[--top];
      const int li = nodes[3 * p.x], lj = nodes[3 * p.y];
      if (p.x == p.y) {
        if (li < 0) continue;
        stack[top++] = (int2)(li, li);
        stack[top++] = (int2)(li + 1, li + 1);
        stack[top++] = (int2)(li, li + 1);
        continue;
      }
      if (!cs_dop_overlap(node_boxes + CS_DOP_FLOATS * p.x, node_boxes + CS_DOP_FLOATS * p.y)) continue;
      if (li < 0 && lj < 0) {
        const uint f = (uint)nodes[3 * p.x + 1], g = (uint)nodes[3 * p.y + 1];
        if (!cs_faces_adjacent(faces, f, g)) CS_EMIT(pairs, (uint2)(f, g));
      } else if (lj < 0 || (li >= 0 && p.x <= p.y)) {
        stack[top++] = (int2)(li, p.y);
        stack[top++] = (int2)(li + 1, p.y);
      } else {
        stack[top++] = (int2)(p.x, lj);
        stack[top++] = (int2)(p.x, lj + 1);
      }
    }
  }
  CS_EMITTER_END(pairs);
}

/* owned: bits 0-2 face vertex k owned by the face, bits 3-5 face edge k. */
__kernel void cs_decompose(__global const uint2* pairs, const uint n, __global const uint* faces,
                           __global const uint* face_edges, __global const uint* owned,
                           __global const float* vertex_boxes, __global const float* edge_boxes,
                           __global const float* face_boxes, CS_EMITTER_PARAMS(uint2, vf),
                           CS_EMITTER_PARAMS(uint2, ee))
{
  CS_EMITTER_BEGIN(vf);
  CS_EMITTER_BEGIN(ee);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint fa = pairs[i].x, fb = pairs[i].y;
    const uint oa = owned[fa], ob = owned[fb];
    for (uint k = 0; k < 3; ++k) {
      const uint va = faces[3 * fa + k], vb = faces[3 * fb + k];
      if ((oa & (1u << k)) && cs_dop_overlap(vertex_boxes + CS_DOP_FLOATS * va, face_boxes + CS_DOP_FLOATS * fb))
        CS_EMIT(vf, (uint2)(va, fb));
      if ((ob & (1u << k)) && cs_dop_overlap(vertex_boxes + CS_DOP_FLOATS * vb, face_boxes + CS_DOP_FLOATS * fa))
        CS_EMIT(vf, (uint2)(vb, fa));
    }
    for (uint a = 0; a < 3; ++a) {
      if (!(oa & (8u << a))) continue;
      const uint ea = face_edges[3 * fa + a];
      for (uint b = 0; b < 3; ++b) {
        if (!(ob & (8u << b))) continue;
        const uint eb = face_edges[3 * fb + b];
        if (cs_dop_overlap(edge_boxes + CS_DOP_FLOATS * ea, edge_boxes + CS_DOP_FLOATS * eb))
          CS_EMIT(ee, (uint2)(min(ea, eb), max(ea, eb)));
      }
    }
  }
  CS_EMITTER_END(vf);
  CS_EMITTER_END(ee);
}

/* Flags orphan pairs (first, second) whose boxes overlap: vertex-face pairs read
 * `first_boxes` = vertex boxes and `second_boxes` = face boxes, edge-edge pairs edge
 * boxes for both. */
__kernel void cs_cull_pairs(__global const uint2* pairs, const uint n, __global const float* first_boxes,
                            __global const float* second_boxes, __global uint* keep)
{
  const uint i = get_global_id(0);
  if (i >= n) return;
  keep[i] = cs_dop_overlap(first_boxes + CS_DOP_FLOATS * pairs[i].x, second_boxes + CS_DOP_FLOATS * pairs[i].y);
}
