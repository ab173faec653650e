/* Kernels of a stream graph that has nothing to do with geometry, used to test the
 * scheduler against a host computation (see tests/runtime/stream_test_reference.hpp). */
#include "runtime/registration.h"

uint test_hash(uint x)
{
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

/* Rarely a burst of 40, else 0..4: the bursts overflow first-guess segments. */
uint test_emit_count(uint value)
{
  const uint h = test_hash(value);
  return (h & 63u) == 0 ? 40u : h % 5u;
}

__kernel void test_expand(__global const uint* values, const uint n, CS_EMITTER_PARAMS(uint2, pairs))
{
  CS_EMITTER_BEGIN(pairs);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint m = test_emit_count(values[i]);
    for (uint k = 0; k < m; ++k) CS_EMIT(pairs, (uint2)(i, k));
  }
  CS_EMITTER_END(pairs);
}

/* A generation of values: value v begets test_emit_count(v) values, the way a BVTT
 * front update turns a front into the next one. */
__kernel void test_beget(__global const uint* values, const uint n, CS_EMITTER_PARAMS(uint, next))
{
  CS_EMITTER_BEGIN(next);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint v = values[i], m = test_emit_count(v);
    for (uint k = 0; k < m; ++k) CS_EMIT(next, test_hash(v + k + 1u));
  }
  CS_EMITTER_END(next);
}

__kernel void test_square(__global const uint* values, const uint n, __global uint* squares)
{
  const uint i = get_global_id(0);
  if (i < n) squares[i] = values[i] * values[i];
}

__kernel void test_keep(__global const uint2* pairs, const uint n, __global uint* keep)
{
  const uint i = get_global_id(0);
  if (i < n) keep[i] = test_hash(pairs[i].x * 31u + pairs[i].y) % 3u != 0u;
}

/* Two outputs from one pass, a small one first: the first coordinate of every pair
 * whose second is a multiple of four, then a copy of every pair. */
__kernel void test_tag_and_copy(__global const uint2* pairs, const uint n, CS_EMITTER_PARAMS(uint, tags),
                                CS_EMITTER_PARAMS(uint2, copies))
{
  CS_EMITTER_BEGIN(tags);
  CS_EMITTER_BEGIN(copies);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 p = pairs[i];
    if (p.y % 4u == 0u) CS_EMIT(tags, p.x);
    CS_EMIT(copies, p);
  }
  CS_EMITTER_END(tags);
  CS_EMITTER_END(copies);
}

/* Two outputs from one pass, the way triangle pairs split into VF and EE features. */
__kernel void test_split(__global const uint2* pairs, const uint n, __global const uint* squares,
                         CS_EMITTER_PARAMS(uint, even), CS_EMITTER_PARAMS(uint4, odd))
{
  CS_EMITTER_BEGIN(even);
  CS_EMITTER_BEGIN(odd);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint2 p = pairs[i];
    const uint s = squares[p.x];
    if ((s + p.y) % 2u == 0u) {
      CS_EMIT(even, s + p.y);
    } else {
      for (uint k = 0; k < p.y % 3u + 1u; ++k) CS_EMIT(odd, (uint4)(p.x, p.y, k, s));
    }
  }
  CS_EMITTER_END(even);
  CS_EMITTER_END(odd);
}

__kernel void test_flag_odd(__global const uint* values, const uint n, __global uint* keep)
{
  const uint i = get_global_id(0);
  if (i < n) keep[i] = values[i] & 1u;
}

/* In-place updates, for the scheduler's update() passes. */
__kernel void test_plus_one(__global uint* values, const uint n)
{
  const uint i = get_global_id(0);
  if (i < n) values[i] += 1u;
}

/* Seven buffers added into an eighth: a launch that binds as many buffers as the
 * pipeline's busier kernels, for bench_runtime's host costs. */
__kernel void test_sum_into_first(__global uint* a, __global const uint* b, __global const uint* c,
                                  __global const uint* d, __global const uint* e, __global const uint* f,
                                  __global const uint* g, __global const uint* h, const uint n)
{
  const uint i = get_global_id(0);
  if (i < n) a[i] += b[i] + c[i] + d[i] + e[i] + f[i] + g[i] + h[i];
}

__kernel void test_times_two(__global uint* values, const uint n)
{
  const uint i = get_global_id(0);
  if (i < n) values[i] *= 2u;
}

/* A running minimum, for the scheduler's lower() passes: every value's expansion as in
 * test_expand, and its hash taken into least[value % m]. */
__kernel void test_clear_least(const uint m, __global uint* least)
{
  const uint i = get_global_id(0);
  if (i < m) least[i] = 0xffffffffu;
}

__kernel void test_expand_lowering(__global const uint* values, const uint n, const uint m, __global uint* least,
                                   CS_EMITTER_PARAMS(uint2, pairs))
{
  CS_EMITTER_BEGIN(pairs);
  const uint i = get_global_id(0);
  if (i < n) {
    const uint count = test_emit_count(values[i]);
    for (uint k = 0; k < count; ++k) CS_EMIT(pairs, (uint2)(i, k));
    atomic_min(&least[values[i] % m], test_hash(values[i]));
  }
  CS_EMITTER_END(pairs);
}

__kernel void test_copy(__global const uint* from, const uint n, __global uint* to)
{
  const uint i = get_global_id(0);
  if (i < n) to[i] = from[i];
}

/* A work list: input i splits into two items a round until depth test_depth(value),
 * and each leaf counts itself in the input's state, so input i ends with 2^depth, twice
 * that where the seed gives it two trees. With `deepest` set, the state also holds,
 * after the n counts, each input's deepest leaf (the work list's extra state), and the
 * count comes out shifted left by four bits with the depth below. A round replayed
 * after an overflow (runtime/worklist.h) counts no leaf twice. */
#include "runtime/worklist.h"

uint test_depth(uint value) { return test_hash(value ^ 0x9e3779b9u) % 12u; }

/* Inputs whose value is odd get a second tree from the seed. */
__kernel void test_tree_seed(__global const uint* values, const uint n, const uint deepest, __global uint* leaves,
                             __global uint2* list, __global uint* counts, const uint capacity)
{
  const uint i = get_global_id(0);
  cs_worklist_seed_begin(counts, n);
  if (i >= n) return;
  list[i] = (uint2)(i, 0);
  leaves[i] = 0;
  if (deepest) leaves[n + i] = 0;
  if (values[i] & 1u) {
    const uint at = cs_worklist_seed_index(counts, n, capacity);
    if (at < capacity) list[at] = (uint2)(i, 0);
  }
}

__kernel void test_tree_round(__global const uint* values, const uint n, const uint deepest, __global uint* leaves,
                              __global const uint2* in, __global uint2* out, __global uint* counts, const uint round,
                              const uint capacity)
{
  __local uint group[2];
  const uint items = cs_worklist_items(counts, round, capacity);
  const int replay = cs_worklist_replay(counts, round);
  for (uint base = get_group_id(0) * get_local_size(0); base < items; base += get_global_size(0)) {
    const uint i = base + get_local_id(0);
    uint2 item = (uint2)(0, 0);
    uint k = 0;
    if (i < items) {
      item = in[i];
      if (item.y < test_depth(values[item.x])) k = 2;
      else if (!replay) {
        atomic_inc(&leaves[item.x]);
        if (deepest) atomic_max(&leaves[n + item.x], item.y);
      }
    }
    const uint at = cs_worklist_append(group, counts, round, k);
    for (uint j = 0; j < k; ++j)
      if (cs_worklist_fits(counts, capacity, at + j)) out[at + j] = (uint2)(item.x, item.y + 1);
  }
  cs_worklist_check_loops(counts, round);
}

__kernel void test_tree_finish(__global const uint* values, const uint n, const uint deepest,
                               __global const uint* leaves, CS_EMITTER_PARAMS(uint2, counted))
{
  CS_EMITTER_BEGIN(counted);
  const uint i = get_global_id(0);
  if (i < n) CS_EMIT(counted, (uint2)(i, deepest ? leaves[i] << 4 | leaves[n + i] : leaves[i]));
  CS_EMITTER_END(counted);
}

/* One work-item per item of two streams, the second after the first. */
__kernel void test_concatenate(__global const uint* a, const uint na, __global const uint* b, const uint nb,
                               CS_EMITTER_PARAMS(uint, both))
{
  CS_EMITTER_BEGIN(both);
  const uint i = get_global_id(0);
  if (i < na) CS_EMIT(both, a[i]);
  else if (i < na + nb) CS_EMIT(both, b[i - na]);
  CS_EMITTER_END(both);
}
