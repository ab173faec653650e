#ifndef CSTREAMS_CCD_EARLIEST_H
#define CSTREAMS_CCD_EARLIEST_H
/* The earliest time of impact per object, a word each: times as floats rounded down
 * (so still lower bounds) and, being non-negative, ordered as their bits are, so an
 * atomic minimum on the bits is a minimum on the times. Built with CS_REAL_DOUBLE. */
#include "real.h"

#define CS_NONE 0xffffffffu /* no object, or no time yet: above every time's bits */

/* t's bits as a float no later than it. */
inline uint cs_time_key(const real t)
{
#if CS_REAL_DOUBLE
  float f = (float)t;
  if ((double)f > t) f = nextafter(f, 0.0f);
  return as_uint(f);
#else
  return as_uint(t);
#endif
}

/* A minimum only falls, so a time no earlier than what is already there needs no atomic. */
inline void cs_lower_earliest(__global uint* earliest, const uint object, const uint key)
{
  if (key < earliest[object]) atomic_min(&earliest[object], key);
}

/* The objects of pair p's two features: the first's, then the second's. */
inline void cs_pair_objects(const uint2 p, const uint vertex_face, __global const uint* faces,
                            __global const uint* edges, __global const uint* vertex_object, uint objects[2])
{
  objects[0] = vertex_object[vertex_face ? p.x : edges[2 * p.x]];
  objects[1] = vertex_object[vertex_face ? faces[3 * p.y] : edges[2 * p.y]];
}

#endif
