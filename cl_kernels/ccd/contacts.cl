/* Contacts as the host reports them (contacts.hpp), made on the device so that they
 * come back sorted (runtime/sort.cl) in one read. Each found pair of one kind becomes
 * a record of eight words that orders, word by word, as canonical_less does:
 *   kind << 31 | object_a, object_b, v0, v1, v2, v3, time's high word, time's low word
 * with object-local vertex ids. Object ids fit 31 bits: every object has three
 * vertices of the 2^32 that vertex ids can name. Times are never negative, so their
 * bits order as the times do; a single-precision time is its float's bits and a zero
 * low word. Once sorted, cs_contacts_as_host lays them out as the host's Contact. */
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

/* The double of a non-negative finite float, from its bits: devices without fp64
 * widen single-precision times too. A subnormal's leading bit becomes the implicit one. */
inline ulong cs_double_bits_of_float(const uint f)
{
  if (f == 0) return 0;
  const uint e = f >> 23, m = f & 0x7fffffu;
  if (e) return (ulong)(e + 896u) << 52 | (ulong)m << 29;
  const uint p = 31u - clz(m);
  return (ulong)(p + 874u) << 52 | (ulong)(m ^ (1u << p)) << (52u - p);
}

/* The sorted records as the host's Contact (contacts.hpp; contact_readback.cpp checks
 * its layout): ten words, the kind in the first (its byte and three zero bytes of
 * padding), object_a, object_b, v[4], four bytes of padding, the time as a double, low
 * word first. The host hands out what it reads, converting nothing: on cloth-ball that
 * conversion cost 0.19 ms on sixteen cores. Host and device are little-endian. */
__kernel void cs_contacts_as_host(__global const uint8* records, const uint n, const uint double_time,
                                  __global uint* contacts)
{
  const uint i = get_global_id(0);
  if (i >= n) return;
  const uint8 r = records[i];
  const ulong time = double_time ? (ulong)r.s6 << 32 | r.s7 : cs_double_bits_of_float(r.s6);
  __global uint* c = contacts + 10 * (size_t)i;
  c[0] = r.s0 >> 31;
  c[1] = r.s0 & 0x7fffffffu;
  c[2] = r.s1;
  c[3] = r.s2;
  c[4] = r.s3;
  c[5] = r.s4;
  c[6] = r.s5;
  c[7] = 0;
  c[8] = (uint)time;
  c[9] = (uint)(time >> 32);
}
