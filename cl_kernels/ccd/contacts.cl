/* Contacts as the host reports them (contacts.hpp), made on the device so that they
 * come back sorted (runtime/sort.cl) in one read. Each found pair of one kind becomes
 * a record of eight words that orders, word by word, as canonical_less does:
 *   kind << 31 | object_a, object_b, v0, v1, v2, v3, time's high word, time's low word
 * with object-local vertex ids. Object ids fit 31 bits: every object has three
 * vertices of the 2^32 that vertex ids can name. Times are never negative, so their
 * bits order as the times do; a single-precision time is its float's bits and a zero
 * low word. */
#include "streams.h"

/* One found pair c: (feature a, feature b, time bits) as narrow_phase_pairs.cl emits
 * them; vertex_face: a is a vertex and b a face, else both are edges. */
inline uint8 cs_contact_record(const uint4 c, const uint vertex_face, const uint double_time,
                               __global const uint* faces, __global const uint2* edges,
                               __global const uint* vertex_object, __global const uint* first_vertex)
{
  uint object_a, object_b;
  uint4 v;
  if (vertex_face) {
    object_a = vertex_object[c.x];
    object_b = vertex_object[faces[3 * c.y]];
    const uint fa = first_vertex[object_a], fb = first_vertex[object_b];
    v = (uint4)(c.x - fa, faces[3 * c.y] - fb, faces[3 * c.y + 1] - fb, faces[3 * c.y + 2] - fb);
  } else {
    uint2 ea = edges[c.x], eb = edges[c.y];
    object_a = vertex_object[ea.x];
    object_b = vertex_object[eb.x];
    if (object_a > object_b) {
      const uint o = object_a;
      object_a = object_b;
      object_b = o;
      const uint2 e = ea;
      ea = eb;
      eb = e;
    }
    ea -= first_vertex[object_a];
    eb -= first_vertex[object_b];
    if (object_a == object_b && (eb.x < ea.x || (eb.x == ea.x && eb.y < ea.y))) {
      const uint2 e = ea;
      ea = eb;
      eb = e;
    }
    v = (uint4)(ea, eb);
  }
  const uint2 time = double_time ? (uint2)(c.w, c.z) : (uint2)(c.z, 0);
  return (uint8)((vertex_face ? 0u : 1u) << 31 | object_a, object_b, v, time);
}

CS_DEFINE_STREAM_ITEM(uint4)

/* The records of every contact stream of a step in one launch: the pairs of stream k
 * go after those of the streams before it. */
__kernel void cs_contact_records(CS_FOUR_STREAMS(uint4), const uint double_time, __global const uint* faces,
                                 __global const uint2* edges, __global const uint* vertex_object,
                                 __global const uint* first_vertex, __global uint8* records)
{
  const uint i = get_global_id(0);
  uint4 c;
  uint vertex_face;
  if (cs_stream_item_uint4(i, CS_FOUR_STREAM_ARGS, &c, &vertex_face))
    records[i] = cs_contact_record(c, vertex_face, double_time, faces, edges, vertex_object, first_vertex);
}
