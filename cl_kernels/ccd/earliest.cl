/* The earliest time of impact per object, without reading back the contacts: times
 * are floats rounded down (so still lower bounds) and, being non-negative, order as
 * their bits do, so an atomic minimum on the bits is a minimum on the times. */
#pragma OPENCL FP_CONTRACT OFF
#if CS_REAL_DOUBLE
#if CS_FP64_AMD
#pragma OPENCL EXTENSION cl_amd_fp64 : enable
#else
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
#endif
#include "streams.h"

__kernel void cs_clear_earliest(const uint objects, __global uint* earliest)
{
  const uint i = get_global_id(0);
  if (i < objects) earliest[i] = as_uint(1.0f);
}

/* One contact of `contacts`: (feature a, feature b, time bits) as narrow_phase_pairs.cl
 * emits them, built with the same CS_REAL_DOUBLE; vertex_face: a is a vertex and b a
 * face, else both are edges. */
inline void cs_earliest_of(const uint4 c, const uint vertex_face, __global const uint* faces,
                           __global const uint* edges, __global const uint* vertex_object, __global uint* earliest)
{
#if CS_REAL_DOUBLE
  const double d = as_double(c.zw);
  float t = (float)d;
  if ((double)t > d) t = nextafter(t, 0.0f);
#else
  const float t = as_float(c.z);
#endif
  const uint a = vertex_object[vertex_face ? c.x : edges[2 * c.x]];
  const uint b = vertex_object[vertex_face ? faces[3 * c.y] : edges[2 * c.y]];
  /* Objects are few and contacts many, so atomics on one object queue up; a minimum
   * only falls, so a time no earlier than what is already there needs none. */
  if (as_uint(t) < earliest[a]) atomic_min(&earliest[a], as_uint(t));
  if (as_uint(t) < earliest[b]) atomic_min(&earliest[b], as_uint(t));
}

CS_DEFINE_STREAM_ITEM(uint4)

/* Every contact stream of a step in one launch. */
__kernel void cs_earliest_toi(CS_FOUR_STREAMS(uint4), __global const uint* faces, __global const uint* edges,
                              __global const uint* vertex_object, __global uint* earliest)
{
  uint4 c;
  uint vertex_face;
  if (cs_stream_item_uint4(get_global_id(0), CS_FOUR_STREAM_ARGS, &c, &vertex_face))
    cs_earliest_of(c, vertex_face, faces, edges, vertex_object, earliest);
}
