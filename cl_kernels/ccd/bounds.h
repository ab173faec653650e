#ifndef CSTREAMS_CCD_BOUNDS_H
#define CSTREAMS_CCD_BOUNDS_H
/* Swept 18-DOPs in single precision, conservative for the exact (double) positions.
 *
 * Positions arrive as floats rounded to nearest, so each exact coordinate lies within
 * [cs_fdown(x), cs_fup(x)]; projections on the six diagonal axes add two such bounds
 * and round outward again. A DOP is 18 floats: lo[0..8] then hi[0..8], axes x, y, z,
 * x+y, x-y, y+z, y-z, z+x, z-x. host/src/float_bounds.cpp repeats this arithmetic
 * operation for operation, so host and device boxes are equal bit for bit. */
#pragma OPENCL FP_CONTRACT OFF

#define CS_DOP_FLOATS 18

/* A face's word: the BVH leaf that holds its box (for the orphan cull, orphans.cl),
 * above six bits of the features the face owns (for the decomposition, broad_phase.cl). */
#define CS_FACE_LEAF_SHIFT 6u
inline uint cs_face_leaf(const uint word) { return word >> CS_FACE_LEAF_SHIFT; }

/* A BVH node in 8 bytes, half of what (first child, face, parent, depth) take apart:
 * x is the first child of an inner node (>= 0) or -1 - face of a leaf; y is parent + 1
 * above CS_NODE_DEPTH_BITS of depth in its own tree. The host holds a scene to fewer
 * than 2^26 nodes and 40 levels (ccd_graph.cpp), which these bits cover. */
#define CS_NODE_DEPTH_BITS 6u
inline int cs_node_face(const int2 node) { return -1 - node.x; }
inline int cs_node_parent(const int2 node) { return (int)((uint)node.y >> CS_NODE_DEPTH_BITS) - 1; }
inline int cs_node_depth(const int2 node) { return (int)((uint)node.y & ((1u << CS_NODE_DEPTH_BITS) - 1u)); }

inline float cs_fdown(float x) { return x - (fabs(x) * 0x1p-23f + FLT_MIN); }
inline float cs_fup(float x) { return x + (fabs(x) * 0x1p-23f + FLT_MIN); }

inline void cs_dop_empty(float lo[9], float hi[9])
{
  for (int k = 0; k < 9; ++k) {
    lo[k] = INFINITY;
    hi[k] = -INFINITY;
  }
}

inline void cs_dop_add(float lo[9], float hi[9], const float x, const float y, const float z)
{
  const float xl = cs_fdown(x), xh = cs_fup(x), yl = cs_fdown(y), yh = cs_fup(y), zl = cs_fdown(z), zh = cs_fup(z);
  const float l[9] = {xl, yl, zl, cs_fdown(xl + yl), cs_fdown(xl - yh), cs_fdown(yl + zl), cs_fdown(yl - zh),
                      cs_fdown(zl + xl), cs_fdown(zl - xh)};
  const float h[9] = {xh, yh, zh, cs_fup(xh + yh), cs_fup(xh - yl), cs_fup(yh + zh), cs_fup(yh - zl),
                      cs_fup(zh + xh), cs_fup(zh - xl)};
  for (int k = 0; k < 9; ++k) {
    lo[k] = fmin(lo[k], l[k]);
    hi[k] = fmax(hi[k], h[k]);
  }
}

/* Grows every slab by the separation in space: by s on the coordinate axes and by
 * s * sqrt(2) (rounded up) on the diagonals, whose axis vectors have that length. */
inline void cs_dop_inflate(float lo[9], float hi[9], const float separation)
{
  if (separation <= 0) return;
  const float diagonal = cs_fup(separation * 1.41421366f);
  for (int k = 0; k < 9; ++k) {
    const float grow = k < 3 ? separation : diagonal;
    lo[k] = cs_fdown(lo[k] - grow);
    hi[k] = cs_fup(hi[k] + grow);
  }
}

/* The swept box of `count` vertices over the step. */
inline void cs_swept_dop(__global const float* x0, __global const float* x1, const uint* vertices, const int count,
                         const float separation, float box[CS_DOP_FLOATS])
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
    box[k] = lo[k];
    box[9 + k] = hi[k];
  }
}

/* A vertex's box is made where it is read, from its two positions, rather than kept for
 * every vertex: the decomposition and the orphan cull read few (n-body: 5.1 MiB). */
inline void cs_vertex_dop(__global const float* x0, __global const float* x1, const uint v, const float separation,
                          float box[CS_DOP_FLOATS])
{
  cs_swept_dop(x0, x1, &v, 1, separation, box);
}

inline int cs_dops_apart(const float x[CS_DOP_FLOATS], const float y[CS_DOP_FLOATS])
{
  int apart = 0;
  for (int k = 0; k < 9; ++k) apart |= (x[k] > y[9 + k]) | (y[k] > x[9 + k]);
  return apart;
}

/* A box read or written as nine float2: a box starts 72 bytes after the one before, so
 * pairs of floats are aligned, and that takes half the loads and stores of floats one by
 * one (H100, cloth-ball's refit: 0.08 -> 0.04 ms). */
inline void cs_dop_load(__global const float* box, float x[CS_DOP_FLOATS])
{
  for (int k = 0; k < CS_DOP_FLOATS / 2; ++k) {
    const float2 u = ((__global const float2*)box)[k];
    x[2 * k] = u.x;
    x[2 * k + 1] = u.y;
  }
}

inline void cs_dop_store(const float x[CS_DOP_FLOATS], __global float* box)
{
  for (int k = 0; k < CS_DOP_FLOATS / 2; ++k) ((__global float2*)box)[k] = (float2)(x[2 * k], x[2 * k + 1]);
}

/* Whether box x, already read, and box b are apart. On a GPU b is read whole before any
 * slab is compared: loads that an early return could skip are issued one after another,
 * each waiting for the one before (on the H200 the front update and the decomposition
 * took a fifth longer so). On a CPU the early return wins (pocl: the front update 180 ->
 * 130 ms on cloth-ball). */
inline int cs_dop_apart(const float x[CS_DOP_FLOATS], __global const float* b)
{
#if CS_CPU
  for (int k = 0; k < 9; ++k)
    if (x[k] > b[9 + k] || b[k] > x[9 + k]) return 1;
  return 0;
#else
  float y[CS_DOP_FLOATS];
  cs_dop_load(b, y);
  return cs_dops_apart(x, y);
#endif
}

/* Whether boxes a and b overlap; on a CPU a's slabs are read only as far as needed. */
inline int cs_dop_overlap(__global const float* a, __global const float* b)
{
#if CS_CPU
  for (int k = 0; k < 9; ++k)
    if (a[k] > b[9 + k] || b[k] > a[9 + k]) return 0;
  return 1;
#else
  float x[CS_DOP_FLOATS];
  cs_dop_load(a, x);
  return !cs_dop_apart(x, b);
#endif
}

#endif
