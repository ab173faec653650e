/* The earliest time of impact per object, without reading back the contacts
 * (earliest.h). */
#include "earliest.h"
#include "runtime/common.h"
#include "streams.h"

__kernel void cs_clear_earliest(const uint objects, __global uint* earliest)
{
  const uint i = get_global_id(0);
  if (i < objects) earliest[i] = as_uint(1.0f);
}

/* Contact c's time as the bits of a float no later than it. c is (feature a, feature b,
 * time bits) as narrow_phase_pairs.cl emits them, built with the same CS_REAL_DOUBLE. */
inline uint cs_contact_time_key(const uint4 c)
{
#if CS_REAL_DOUBLE
  return cs_time_key(as_double(c.zw));
#else
  return c.z;
#endif
}

CS_DEFINE_STREAM_ITEM(uint4)

/* Every contact stream of a step in one launch; a stream's vertex_face: its contacts are
 * of a vertex and a face, else of two edges. Objects are few and contacts many, so
 * atomics on one object's word queue up: a group takes the minimum over the objects of
 * its first contact in local memory first (a group's contacts mostly share them: the
 * cloth and the ball on cloth-ball), and reaches their words once. */
CS_GROUP_KERNEL void cs_earliest_toi(CS_FOUR_STREAMS(uint4), __global const uint* faces, __global const uint* edges,
                                     __global const uint* vertex_object, __global uint* earliest)
{
  __local uint objects[2], least[2];
  uint4 c;
  uint vertex_face, mine[2] = {CS_NONE, CS_NONE}, key = 0;
  if (cs_stream_item_uint4(get_global_id(0), CS_FOUR_STREAM_ARGS, &c, &vertex_face)) {
    key = cs_contact_time_key(c);
    cs_pair_objects(c.xy, vertex_face, faces, edges, vertex_object, mine);
  }
  const uint lid = get_local_id(0);
  if (lid < 2) {
    objects[lid] = mine[lid];
    least[lid] = CS_NONE;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int k = 0; k < 2; ++k) {
    if (mine[k] == CS_NONE) continue;
    if (mine[k] == objects[0])
      atomic_min(&least[0], key);
    else if (mine[k] == objects[1])
      atomic_min(&least[1], key);
    else
      cs_lower_earliest(earliest, mine[k], key);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid < 2 && least[lid] != CS_NONE) cs_lower_earliest(earliest, objects[lid], least[lid]);
}
