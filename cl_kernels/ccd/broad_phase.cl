/* Broad phase of a scene: BVTT front update over a forest of BVHs (one per object) to
 * non-adjacent triangle pairs, and their decomposition into vertex-face and edge-edge
 * pairs by feature ownership, less those whose features stay apart through the step
 * (orphans.cl culls the orphan pairs). Boxes are 18 floats (bounds.h). Ids are global:
 * every object's vertices, edges, faces and nodes lie in one range of the scene's
 * streams.
 *
 * nodes: int2 (first child, or -1 - face for a leaf; parent and depth, bounds.h).
 * A BVTT node is a pair of tree nodes (i, j); i == j is a node against itself. A pair
 * of distinct nodes descends the shallower one (the first on a tie, never a leaf), so
 * the parent of (i, j) is (parent(i), j) when i is deeper, else (i, parent(j)); a
 * node against itself has children (l, l + 1), (l, l), (l + 1, l + 1), the first being
 * its first child. The level of (i, j) is depth(i) + depth(j), which grows along
 * every BVTT edge. */
#include "runtime/loop_trips.h"
#include "runtime/registration.h"
#include "bounds.h"

/* Along a depth-first path, a node against itself pushes three pairs (net +2) and
 * descends both sides, a pair of nodes pushes two (net +1) and descends one side, so
 * the stack holds at most 2 * depth + 1 pairs: 128 covers trees of up to 40 levels,
 * and the host refuses deeper ones. */
#define CS_BVTT_STACK 128

#if CS_LOOP_TRIPS
/* On a device that ends loops early (runtime/loop_trips.h), the stack trips a search
 * may make: each trip may also run the short loops of a box test and an adjacency test
 * (about twenty trips where the compiler keeps them as loops), and the climbs before
 * it take a trip a level. */
#define CS_SEARCH_TRIPS (CS_LOOP_TRIPS / 32u)
#endif

/* Built with CS_KEEP_FRONT=1 the update emits the next front (front modes exact and
 * deferred); with 0 the front is a fixed set of seeds, searched every step. */
#ifndef CS_KEEP_FRONT
#define CS_KEEP_FRONT 0
#endif
#if CS_KEEP_FRONT
#define CS_FRONT_PARAMS CS_EMITTER_PARAMS(int2, next_front),
#define CS_FRONT_BEGIN CS_EMITTER_BEGIN(next_front)
#define CS_FRONT_EMIT(p) CS_EMIT(next_front, p)
#define CS_FRONT_END CS_EMITTER_END(next_front)
#else
#define CS_FRONT_PARAMS
#define CS_FRONT_BEGIN (void)0
#define CS_FRONT_EMIT(p) (void)0
#define CS_FRONT_END (void)0
#endif

inline int cs_faces_adjacent(__global const uint* faces, const uint f, const uint g)
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (faces[3 * f + i] == faces[3 * g + j]) return 1;
  return 0;
}

inline int cs_pair_overlaps(__global const float* boxes, const int2 p)
{
  return p.x == p.y || cs_dop_overlap(boxes + CS_DOP_FLOATS * p.x, boxes + CS_DOP_FLOATS * p.y);
}

/* Whether a pair of distinct nodes descends its first node. */
inline int cs_descends_first(const int2 a, const int2 b)
{
  return a.x >= 0 && (b.x < 0 || cs_node_depth(a) <= cs_node_depth(b));
}

/* The BVTT parent of p, or (-1, -1) for a pair of two roots (a seed of the front). */
inline int2 cs_bvtt_parent(__global const int2* nodes, const int2 p)
{
  const int2 a = nodes[p.x], b = nodes[p.y];
  const int pa = cs_node_parent(a), pb = cs_node_parent(b);
  if (p.x == p.y) return pa < 0 ? (int2)(-1, -1) : (int2)(pa, pa);
  if (pa >= 0 && pa == pb) return (int2)(pa, pa);
  if (pa < 0 && pb < 0) return (int2)(-1, -1);
  return cs_node_depth(a) > cs_node_depth(b) ? (int2)(pa, p.y) : (int2)(p.x, pb);
}

inline int cs_is_first_child(__global const int2* nodes, const int2 parent, const int2 child)
{
  const int2 a = nodes[parent.x], b = nodes[parent.y];
  if (parent.x == parent.y) return child.x == a.x && child.y == a.x + 1;
  return cs_descends_first(a, b) ? child.x == a.x : child.y == b.x;
}

inline uint cs_level(__global const int2* nodes, const int2 p)
{
  return (uint)(cs_node_depth(nodes[p.x]) + cs_node_depth(nodes[p.y]));
}

/* A search's pairs waiting for a work-item of the group (cs_front_update): eight a
 * work-item, 16 KiB in groups of 256, within the 32 KiB of local memory an HD 5870
 * gives a group. */
#define CS_SHARED_SEARCH (8 * CS_WG_SIZE)

/* A pair waiting in a search, with whether its boxes are known to overlap (the pair a
 * search starts from was tested before it waits). */
inline int2 cs_waiting(const int2 p, const int overlap_known) { return overlap_known ? (int2)(-1 - p.x, p.y) : p; }

/* What a pair does in the front update (cs_front_update), each where its flag is set:
 * it places a pair in the next front, reports the faces of two overlapping leaves, or
 * waits to be searched. */
#define CS_EMITS_FRONT 1
#define CS_EMITS_FACES 2
#define CS_SEARCHES 4

/* The level of q, the BVTT parent of a pair p at `level`: a node against itself sits two
 * levels above its children and above a pair of siblings, any other pair one. */
inline uint cs_parent_level(const int2 q, const uint level) { return level - (q.x == q.y ? 2u : 1u); }

/* A pair of the current front before the group's search: one deeper than `cap` stands
 * for its ancestor at the cap; one whose boxes are apart climbs as far as boxes stay
 * apart, but to no level above `climb_floor`, and takes its place in the next front
 * where it is on its ancestor's chain of first children; two overlapping leaves are
 * settled here. Returns what it does (CS_EMITS_*, or CS_SEARCHES with `search` the
 * pair to search as it waits, cs_waiting).
 *
 * The floor bounds what one pair's search may cost once its boxes overlap again: a
 * whole subtree falls to the work-group that holds the pair, and pairs that climbed
 * together sit side by side in the front, in one group. On the 1.5M-triangle sheet,
 * pairs climbed for twenty steps to near the roots, and the step where contact surged
 * took two launches of the front update of 45-99 ms each, most groups idle; with pairs
 * kept from climbing above level 18, 24 or 30 alike, 16-21 ms each (H200). */
inline int cs_front_start(int2 p, __global const int2* nodes, __global const float* node_boxes,
                          __global const uint* faces, const uint cap, const uint climb_floor, int2* front,
                          uint2* face_pair, int2* search)
{
  int live = 1;
  while (live && cs_level(nodes, p) > cap) {
    const int2 q = cs_bvtt_parent(nodes, p);
    live = cs_is_first_child(nodes, q, p);
    p = q;
  }
  if (!live) return 0;
  uint level = cs_level(nodes, p);
  int apart = 0;
  if (p.x != p.y) {
    /* Most of a settled front's pairs are apart, and so they test their parent too.
     * The parent keeps one of the pair's nodes, so that node's box is read once for
     * both tests (H200: cloth-ball's front update 0.350 -> 0.335 ms with the leaves'
     * path below). */
    const int2 q = cs_bvtt_parent(nodes, p);
    const int keeps_y = q.y == p.y;
    float kept[CS_DOP_FLOATS];
    cs_dop_load(node_boxes + CS_DOP_FLOATS * (keeps_y ? p.y : p.x), kept);
    apart = cs_dop_apart(kept, node_boxes + CS_DOP_FLOATS * (keeps_y ? p.x : p.y));
    if (apart && CS_KEEP_FRONT) {
      const int parent_overlaps = q.x < 0 || q.x == q.y || cs_parent_level(q, level) < climb_floor ||
                                  !cs_dop_apart(kept, node_boxes + CS_DOP_FLOATS * (keeps_y ? q.x : q.y));
      *front = p;
      if (parent_overlaps) return CS_EMITS_FRONT;
      if (!cs_is_first_child(nodes, q, p)) return 0;
      level = cs_parent_level(q, level);
      p = q;
    }
  }
  if (apart) {
    /* p's boxes are apart, as are those of the pair below it that climbed here. */
    while (CS_KEEP_FRONT) {
      const int2 q = cs_bvtt_parent(nodes, p);
      if (q.x < 0 || cs_parent_level(q, level) < climb_floor || cs_pair_overlaps(node_boxes, q)) {
        *front = p;
        return CS_EMITS_FRONT;
      }
      if (!cs_is_first_child(nodes, q, p)) return 0;
      level = cs_parent_level(q, level);
      p = q;
    }
    return 0;
  }
  if (p.x != p.y && nodes[p.x].x < 0 && nodes[p.y].x < 0) {
    /* Two overlapping leaves, as most of a settled front's other pairs are: settled
     * here rather than through the search. */
    const uint fa = (uint)cs_node_face(nodes[p.x]), fb = (uint)cs_node_face(nodes[p.y]);
    *front = p;
    *face_pair = (uint2)(fa, fb);
    return CS_EMITS_FRONT | (cs_faces_adjacent(faces, fa, fb) ? 0 : CS_EMITS_FACES);
  }
  /* The pair the search starts from overlaps, as tested above; testing its boxes again
   * cost the front update a tenth (H100: cloth-ball 0.40 -> 0.36 ms, n-body 0.56 ->
   * 0.48). */
  *search = cs_waiting(p, p.x != p.y);
  return CS_SEARCHES;
}

/* One pair of the group's search, `w` as it waited (cs_waiting): its children to
 * search, of which it returns how many (a pair of distinct nodes whose boxes overlap
 * descends one of them, a node against itself has three), and what it emits
 * (CS_EMITS_* in `emits`): the pairs where the search stops (boxes apart, or two
 * leaves) and the overlapping ones at the cap, below which it goes on without
 * emitting. */
inline int cs_search_visit(const int2 w, __global const int2* nodes, __global const float* node_boxes,
                           __global const uint* faces, const uint cap, int2 children[3], int2* front,
                           uint2* face_pair, int* emits)
{
  const int overlap_known = w.x < 0;
  const int2 q = overlap_known ? (int2)(-1 - w.x, w.y) : w;
  const int2 a = nodes[q.x], b = nodes[q.y];
  const uint level = (uint)(cs_node_depth(a) + cs_node_depth(b));
  const int in_front = CS_KEEP_FRONT && level <= cap;
  *front = q;
  *emits = 0;
  if (q.x == q.y) {
    if (a.x < 0) return 0;
    if (in_front && cap - level < 2) *emits = CS_EMITS_FRONT;
    children[0] = (int2)(a.x, a.x);
    children[1] = (int2)(a.x + 1, a.x + 1);
    children[2] = (int2)(a.x, a.x + 1);
    return 3;
  }
  if (!overlap_known && !cs_dop_overlap(node_boxes + CS_DOP_FLOATS * q.x, node_boxes + CS_DOP_FLOATS * q.y)) {
    if (in_front) *emits = CS_EMITS_FRONT;
    return 0;
  }
  if (a.x < 0 && b.x < 0) {
    const uint fa = (uint)cs_node_face(a), fb = (uint)cs_node_face(b);
    *face_pair = (uint2)(fa, fb);
    *emits = (in_front ? CS_EMITS_FRONT : 0) | (cs_faces_adjacent(faces, fa, fb) ? 0 : CS_EMITS_FACES);
    return 0;
  }
  if (in_front && level == cap) *emits = CS_EMITS_FRONT;
  const int first = cs_descends_first(a, b);
  children[0] = first ? (int2)(a.x, q.y) : (int2)(q.x, b.x);
  children[1] = first ? (int2)(a.x + 1, q.y) : (int2)(q.x, b.x + 1);
  return 2;
}

/* One work-item per pair of the current front (a cut of the BVTT: every pair of
 * leaves lies under exactly one of its pairs). With CS_KEEP_FRONT, emits the next front:
 *  - a pair deeper than `cap` stands for its ancestor at level <= cap;
 *  - a pair whose boxes are apart climbs to its highest ancestor whose boxes are apart,
 *    no higher than `climb` levels above the deepest (cs_front_start); of all the
 *    front pairs under that ancestor, the one on its chain of first children emits it
 *    (exactly one is, since the front is a cut);
 *  - a pair whose boxes overlap is searched: the search emits the pairs where it stops
 *    (boxes apart, or two leaves) and the overlapping pairs at the cap, below which it
 *    goes on without emitting.
 * So the next front is again a cut, no deeper than `cap` (0xffffffff: the exact
 * front). Every search emits the pairs of overlapping leaves whose faces share no vertex.
 *
 * The work-group searches together: the pairs to search wait in local memory, and each
 * round every work-item takes one of the newest (so the group goes deep first and the
 * list stays short), tests it and adds its children. Searched one a work-item, a pair
 * that opened onto a large subtree kept one work-item busy while its group and the
 * device waited: cloth-ball's first step took 34 ms in the front update on the H200,
 * the 1.5M-triangle sheet's surge step 1.7 s. Children that find the list full are
 * searched depth first by the work-item that found them, on its own stack.
 *
 * On a device that ends loops early, a work-item that would need more than
 * CS_SEARCH_TRIPS trips, or whose loops the canary finds cut short, stops the group's
 * search and raises cut[0] (cut[1] holds 1): its outputs are incomplete, and the host
 * runs the step again from a finer front. */
__kernel void cs_front_update(__global const int2* front, const uint n, __global const int2* nodes,
                              __global const float* node_boxes, __global const uint* faces, const uint cap,
                              const uint deepest, const uint climb, __global uint* cut, CS_FRONT_PARAMS
                              CS_EMITTER_PARAMS(uint2, pairs))
{
  CS_FRONT_BEGIN;
  CS_EMITTER_BEGIN(pairs);
  __local int2 waiting[CS_SHARED_SEARCH];
  __local uint waiting_count;
  const uint lid = (uint)get_local_id(0);
  if (lid == 0) waiting_count = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint s = get_global_id(0);
  if (s < n) {
    int2 placed = (int2)(0, 0), search = (int2)(0, 0);
    uint2 face_pair = (uint2)(0, 0);
    /* The floor lies `climb` levels above the deepest a pair may be: the cap where a
     * deferred front has one (its front then shrinks as pairs climb, and the cap rises
     * again), else the trees' deepest pairs of leaves. */
    const uint lowest = min(cap, deepest), climb_floor = lowest > climb ? lowest - climb : 0u;
    const int does =
        cs_front_start(front[s], nodes, node_boxes, faces, cap, climb_floor, &placed, &face_pair, &search);
    if (does & CS_EMITS_FACES) CS_EMIT(pairs, face_pair);
    if (does & CS_EMITS_FRONT) CS_FRONT_EMIT(placed);
    /* One a work-item: the list holds them all. */
    if (does & CS_SEARCHES) waiting[atomic_inc(&waiting_count)] = search;
  }
#if CS_LOOP_TRIPS
  /* Every work-item counts the group's rounds alike, so that all of them leave the
   * rounds together, and its own visits on top. */
  __local int stopped;
  if (lid == 0) stopped = 0;
  uint rounds = 0, trips = 0;
#endif
  for (;;) {
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Every work-item reads the same count: it changes only between the barriers below. */
    const uint count = min(waiting_count, (uint)CS_SHARED_SEARCH);
    if (count == 0) break;
#if CS_LOOP_TRIPS
    if (stopped) break;
    if (++rounds > CS_SEARCH_TRIPS) {
      if (lid == 0) cut[0] = 1u;
      break;
    }
#endif
    const uint take = min(count, (uint)get_local_size(0));
    int2 stack[CS_BVTT_STACK];
    int top = 0;
    if (lid < take) stack[top++] = waiting[count - take + lid];
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) waiting_count = count - take;
    barrier(CLK_LOCAL_MEM_FENCE);
    while (top > 0) {
#if CS_LOOP_TRIPS
      if (rounds + ++trips > CS_SEARCH_TRIPS) {
        cut[0] = 1u;
        stopped = 1;
        break;
      }
#endif
      int2 children[3], placed;
      uint2 face_pair = (uint2)(0, 0);
      int emits;
      const int k = cs_search_visit(stack[--top], nodes, node_boxes, faces, cap, children, &placed, &face_pair, &emits);
      if (emits & CS_EMITS_FACES) CS_EMIT(pairs, face_pair);
      if (emits & CS_EMITS_FRONT) CS_FRONT_EMIT(placed);
      for (int j = 0; j < k; ++j) {
        const uint at = atomic_inc(&waiting_count);
        if (at < CS_SHARED_SEARCH) waiting[at] = children[j];
        else stack[top++] = children[j];
      }
    }
  }
#if CS_LOOP_TRIPS
  if (cs_loops_were_cut(2u + (n == 0u), cut + 1)) cut[0] = 1u;
#endif
  CS_FRONT_END;
  CS_EMITTER_END(pairs);
}

/* The two faces' vertices at both ends of the step: fa's three, then fb's, and the
 * largest magnitude among them. */
inline float cs_pair_corners(__global const uint* faces, const uint fa, const uint fb, __global const float* x0,
                             __global const float* x1, float p0[6][3], float p1[6][3])
{
  float scale = 0;
  for (int j = 0; j < 6; ++j) {
    const uint v = faces[3 * (j < 3 ? fa : fb) + j % 3];
    for (int k = 0; k < 3; ++k) {
      p0[j][k] = x0[3 * v + k];
      p1[j][k] = x1[3 * v + k];
      scale = fmax(scale, fmax(fabs(p0[j][k]), fabs(p1[j][k])));
    }
  }
  return scale;
}

/* The box of points a, b, c (of cs_pair_corners) at one end of the step. */
inline void cs_end_box(const float p[6][3], const int a, const int b, const int c, float lo[3], float hi[3])
{
  for (int k = 0; k < 3; ++k) {
    lo[k] = fmin(fmin(p[a][k], p[b][k]), p[c][k]);
    hi[k] = fmax(fmax(p[a][k], p[b][k]), p[c][k]);
  }
}

/* Whether points (a0, a1, a2) and points (b0, b1, b2) stay more than `margin` apart
 * through the step. A point moves linearly, so the box of moving points at time t lies
 * within the blend of their boxes at the ends, and a gap along an axis between two
 * such blends is linear in t: more than the margin at both ends, it is all along. A
 * swept box, which holds both ends at once, cannot tell features that pass the same
 * place at different times. */
inline int cs_ends_apart(const float p0[6][3], const float p1[6][3], const int a0, const int a1, const int a2,
                         const int b0, const int b1, const int b2, const float margin)
{
  float alo0[3], ahi0[3], alo1[3], ahi1[3], blo0[3], bhi0[3], blo1[3], bhi1[3];
  cs_end_box(p0, a0, a1, a2, alo0, ahi0);
  cs_end_box(p1, a0, a1, a2, alo1, ahi1);
  cs_end_box(p0, b0, b1, b2, blo0, bhi0);
  cs_end_box(p1, b0, b1, b2, blo1, bhi1);
  int apart = 0;
  for (int k = 0; k < 3; ++k)
    apart |= (blo0[k] - ahi0[k] > margin && blo1[k] - ahi1[k] > margin) |
             (alo0[k] - bhi0[k] > margin && alo1[k] - bhi1[k] > margin);
  return apart;
}

/* face_words: bits 0-2 face vertex k owned by the face, bits 3-5 face edge k (between
 * its vertices k and k + 1), then the leaf that holds the face's box (bounds.h). Edge
 * pairs come out as (smaller id, larger id).
 *
 * A feature pair is emitted unless its features stay apart through the step
 * (cs_ends_apart) by more than the separation and what the tests count as touching: 3
 * tolerances at the scale of the pair's coordinates (cs_touching in cubic.h), and 2^-16
 * of that scale for positions rounded to float and the gaps' own rounding. With the
 * faces' six points read once, every test runs on registers; the swept boxes of the
 * faces, edges and vertices that this replaced were read from memory and let through
 * more than twice as many pairs (H200: cloth-ball's decomposition 0.34 -> 0.24 ms and
 * candidates 3.76 -> 1.77 million; n-body's 0.60 -> 0.36 ms, 11.6 -> 2.8 million).
 * Both tests together took 96 registers and cloth-ball's decomposition 0.48 ms. */
__kernel void cs_decompose(__global const uint2* pairs, const uint n, __global const uint* faces,
                           __global const uint* face_edges, __global const uint* face_words,
                           __global const float* x0, __global const float* x1, const float separation,
                           const float tolerance, CS_EMITTER_PARAMS(uint2, vf), CS_EMITTER_PARAMS(uint2, ee))
{
  CS_EMITTER_BEGIN(vf);
  CS_EMITTER_BEGIN(ee);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint fa = pairs[i].x, fb = pairs[i].y;
    const uint oa = face_words[fa] & 63u, ob = face_words[fb] & 63u;
    float p0[6][3], p1[6][3];
    const float scale = cs_pair_corners(faces, fa, fb, x0, x1, p0, p1);
    const float margin = separation + (3 * tolerance + 0x1p-16f) * scale;
    for (int k = 0; k < 3; ++k) {
      if ((oa & (1u << k)) && !cs_ends_apart(p0, p1, k, k, k, 3, 4, 5, margin))
        CS_EMIT(vf, (uint2)(faces[3 * fa + k], fb));
      if ((ob & (1u << k)) && !cs_ends_apart(p0, p1, 3 + k, 3 + k, 3 + k, 0, 1, 2, margin))
        CS_EMIT(vf, (uint2)(faces[3 * fb + k], fa));
    }
    for (int a = 0; a < 3; ++a) {
      if (!(oa & (8u << a))) continue;
      const uint ea = face_edges[3 * fa + a];
      for (int b = 0; b < 3; ++b)
        if ((ob & (8u << b)) && !cs_ends_apart(p0, p1, a, (a + 1) % 3, a, 3 + b, 3 + (b + 1) % 3, 3 + b, margin)) {
          const uint eb = face_edges[3 * fb + b];
          CS_EMIT(ee, (uint2)(min(ea, eb), max(ea, eb)));
        }
    }
  }
  CS_EMITTER_END(vf);
  CS_EMITTER_END(ee);
}
