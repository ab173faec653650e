/* Contacts as the host reports them (contacts.hpp), made on the device so that they
 * come back sorted in one read. Each found pair of one kind becomes a record whose
 * fields, most significant first, order as canonical_less does:
 *   kind (1 bit), object_a, object_b, v0, v1, v2, v3, the time's high word, its low word
 * with object-local vertex ids. Each field takes only the bits the scene's ids need
 * (object_bits for objects, vertex_bits for vertices: ContactReadback), so a record is
 * CS_SORT_WORDS words, not eight: cloth-ball's are four, and its sort took 0.17 ms on
 * the H100 with eight words and 0.13 with four. Times are never negative, so their bits
 * order as the times do; a single-precision time is its float's bits alone.
 *
 * The sort is the runtime's (runtime/sort.h), with its first and last launches here:
 * the block sort makes its records from the contact streams, and the last pass (the
 * block sort itself where one block holds them all) writes them as the host's Contact.
 * Launches of their own took 12 and 16 us of a cloth-ball step on the H100. */
#include "runtime/sort.h"
#include "streams.h"

/* Appends the low `bits` bits of value to the record's fields (bits before `*at` are
 * set): a field may straddle two words. */
inline void cs_put_bits(cs_record* r, uint* at, const uint value, const uint bits)
{
  if (bits == 0) return;
  const uint w = *at / 32, o = *at % 32;
  *at += bits;
  if (o + bits <= 32) {
    r->w[w] |= value << (32 - o - bits);
  } else {
    r->w[w] |= value >> (o + bits - 32);
    r->w[w + 1] |= value << (64 - o - bits);
  }
}

/* The next field of `bits` bits from `*at` on. */
inline uint cs_take_bits(const cs_record* r, uint* at, const uint bits)
{
  if (bits == 0) return 0;
  const uint w = *at / 32, o = *at % 32, mask = bits == 32 ? 0xffffffffu : (1u << bits) - 1u;
  *at += bits;
  if (o + bits <= 32) return (r->w[w] >> (32 - o - bits)) & mask;
  return ((r->w[w] << (o + bits - 32)) | (r->w[w + 1] >> (64 - o - bits))) & mask;
}

/* One found pair c: (feature a, feature b, time bits) as narrow_phase_pairs.cl emits
 * them; vertex_face: a is a vertex and b a face, else both are edges. */
inline cs_record cs_contact_record(const uint4 c, const uint vertex_face, const uint double_time,
                                   const uint object_bits, const uint vertex_bits, __global const uint* faces,
                                   __global const uint2* edges, __global const uint* vertex_object,
                                   __global const uint* first_vertex)
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
  cs_record r;
  for (uint w = 0; w < CS_SORT_WORDS; ++w) r.w[w] = 0;
  uint at = 0;
  cs_put_bits(&r, &at, vertex_face ? 0u : 1u, 1);
  cs_put_bits(&r, &at, object_a, object_bits);
  cs_put_bits(&r, &at, object_b, object_bits);
  cs_put_bits(&r, &at, v.x, vertex_bits);
  cs_put_bits(&r, &at, v.y, vertex_bits);
  cs_put_bits(&r, &at, v.z, vertex_bits);
  cs_put_bits(&r, &at, v.w, vertex_bits);
  if (double_time) {
    cs_put_bits(&r, &at, c.w, 32);
    cs_put_bits(&r, &at, c.z, 32);
  } else {
    cs_put_bits(&r, &at, c.z, 32);
  }
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
inline void cs_store_contact(__global uint* contacts, const uint i, const cs_record* r, const uint double_time,
                             const uint object_bits, const uint vertex_bits)
{
  __global uint* c = contacts + 10 * (size_t)i;
  uint at = 0;
  c[0] = cs_take_bits(r, &at, 1);
  c[1] = cs_take_bits(r, &at, object_bits);
  c[2] = cs_take_bits(r, &at, object_bits);
  for (uint k = 3; k < 7; ++k) c[k] = cs_take_bits(r, &at, vertex_bits);
  c[7] = 0;
  const uint high = cs_take_bits(r, &at, 32);
  const ulong time = double_time ? (ulong)high << 32 | cs_take_bits(r, &at, 32) : cs_double_bits_of_float(high);
  c[8] = (uint)time;
  c[9] = (uint)(time >> 32);
}

CS_DEFINE_STREAM_ITEM(uint4)

/* The sort's first launch over the n pairs of every contact stream of a step (those of
 * stream k after those of the streams before it): each group makes the records of its
 * block and sorts them. Where one block holds them all they go out as Contacts, else
 * to `records` for the merge passes. */
CS_GROUP_KERNEL void cs_contact_sort_blocks(CS_FOUR_STREAMS(uint4), const uint double_time,
                                            const uint object_bits, const uint vertex_bits, __global const uint* faces,
                                            __global const uint2* edges, __global const uint* vertex_object,
                                            __global const uint* first_vertex,
                                            const uint n, const uint block, __global cs_record* records,
                                            __global uint* contacts, __local uint* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  for (uint k = lid; k < block; k += CS_WG_SIZE) {
    uint4 c;
    uint vertex_face;
    const cs_record r = cs_stream_item_uint4(first + k, CS_FOUR_STREAM_ARGS, &c, &vertex_face)
                            ? cs_contact_record(c, vertex_face, double_time, object_bits, vertex_bits, faces, edges,
                                                vertex_object, first_vertex)
                            : cs_record_past_end();
    cs_store_local_record(sorting, block, k, &r);
  }
  cs_sort_local_block(sorting, block);
  for (uint k = lid; k < block && first + k < n; k += CS_WG_SIZE) {
    const cs_record r = cs_local_record(sorting, block, k);
    if (n <= block)
      cs_store_contact(contacts, k, &r, double_time, object_bits, vertex_bits);
    else
      records[first + k] = r;
  }
}

/* The sort's last merge pass (runtime/sort.cl's cs_merge_runs), writing Contacts. */
CS_GROUP_KERNEL void cs_contacts_merged(__global const cs_record* in, const uint n, const uint width,
                                        const uint per_tile, const uint double_time, const uint object_bits,
                                        const uint vertex_bits, __global uint* contacts, __local uint* tile)
{
  __local uint search[8];
  cs_merge_share s = cs_merge_tile(in, n, width, per_tile, tile, search);
  for (; s.o < s.last; ++s.o) {
    const cs_record r = cs_next_merged(&s, tile, per_tile);
    cs_store_contact(contacts, s.first + s.o, &r, double_time, object_bits, vertex_bits);
  }
}
