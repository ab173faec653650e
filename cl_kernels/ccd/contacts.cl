/* Contacts as the host reports them (contacts.hpp), made on the device so that they
 * come back sorted in one read. Each found pair of one kind becomes a record of eight
 * words that orders, word by word, as canonical_less does:
 *   kind << 31 | object_a, object_b, v0, v1, v2, v3, time's high word, time's low word
 * with object-local vertex ids. Object ids fit 31 bits: every object has three
 * vertices of the 2^32 that vertex ids can name. Times are never negative, so their
 * bits order as the times do; a single-precision time is its float's bits and a zero
 * low word.
 *
 * The sort is the runtime's (runtime/sort.h), with its first and last launches here:
 * the block sort makes its records from the contact streams, and the last pass (the
 * block sort itself where one block holds them all) writes them as the host's Contact.
 * Launches of their own took 12 and 16 us of a cloth-ball step on the H100. */
#define CS_SORT_WORDS 8
#include "runtime/sort.h"
#include "streams.h"

/* One found pair c: (feature a, feature b, time bits) as narrow_phase_pairs.cl emits
 * them; vertex_face: a is a vertex and b a face, else both are edges. */
inline cs_record cs_contact_record(const uint4 c, const uint vertex_face, const uint double_time,
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
  const cs_record r = {{(vertex_face ? 0u : 1u) << 31 | object_a, object_b, v.x, v.y, v.z, v.w, time.x, time.y}};
  return r;
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

/* Record r as the host's Contact i (contacts.hpp; contact_readback.cpp checks its
 * layout): ten words, the kind in the first (its byte and three zero bytes of padding),
 * object_a, object_b, v[4], four bytes of padding, the time as a double, low word
 * first. The host hands out what it reads, converting nothing: on cloth-ball that
 * conversion cost 0.19 ms on sixteen cores. Host and device are little-endian. */
inline void cs_store_contact(__global uint* contacts, const uint i, const cs_record* r, const uint double_time)
{
  const ulong time = double_time ? (ulong)r->w[6] << 32 | r->w[7] : cs_double_bits_of_float(r->w[6]);
  __global uint* c = contacts + 10 * (size_t)i;
  c[0] = r->w[0] >> 31;
  c[1] = r->w[0] & 0x7fffffffu;
  c[2] = r->w[1];
  c[3] = r->w[2];
  c[4] = r->w[3];
  c[5] = r->w[4];
  c[6] = r->w[5];
  c[7] = 0;
  c[8] = (uint)time;
  c[9] = (uint)(time >> 32);
}

CS_DEFINE_STREAM_ITEM(uint4)

/* The sort's first launch over the n pairs of every contact stream of a step (those of
 * stream k after those of the streams before it): each group makes the records of its
 * block and sorts them. Where one block holds them all they go out as Contacts, else
 * to `records` for the merge passes. */
CS_GROUP_KERNEL void cs_contact_sort_blocks(CS_FOUR_STREAMS(uint4), const uint double_time,
                                            __global const uint* faces, __global const uint2* edges,
                                            __global const uint* vertex_object, __global const uint* first_vertex,
                                            const uint n, const uint block, __global cs_record* records,
                                            __global uint* contacts, __local uint* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  for (uint k = lid; k < block; k += CS_WG_SIZE) {
    uint4 c;
    uint vertex_face;
    const cs_record r = cs_stream_item_uint4(first + k, CS_FOUR_STREAM_ARGS, &c, &vertex_face)
                            ? cs_contact_record(c, vertex_face, double_time, faces, edges, vertex_object, first_vertex)
                            : cs_record_past_end();
    cs_store_local_record(sorting, block, k, &r);
  }
  cs_sort_local_block(sorting, block);
  for (uint k = lid; k < block && first + k < n; k += CS_WG_SIZE) {
    const cs_record r = cs_local_record(sorting, block, k);
    if (n <= block)
      cs_store_contact(contacts, k, &r, double_time);
    else
      records[first + k] = r;
  }
}

/* The sort's last merge pass (runtime/sort.cl's cs_merge_runs), writing Contacts. */
CS_GROUP_KERNEL void cs_contacts_merged(__global const cs_record* in, const uint n, const uint width,
                                        const uint block, const uint double_time, __global uint* contacts,
                                        __local uint* tile)
{
  __local uint search[8];
  cs_merge_share s = cs_merge_tile(in, n, width, block, tile, search);
  for (; s.o < s.last; ++s.o) {
    const cs_record r = cs_next_merged(&s, tile, block);
    cs_store_contact(contacts, s.first + s.o, &r, double_time);
  }
}
