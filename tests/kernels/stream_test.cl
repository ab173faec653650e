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

__kernel void test_times_two(__global uint* values, const uint n)
{
  const uint i = get_global_id(0);
  if (i < n) values[i] *= 2u;
}
