#ifndef CSTREAMS_RUNTIME_SORT_H
#define CSTREAMS_RUNTIME_SORT_H
/* A work-group's part of the sort of records of CS_SORT_WORDS 32-bit words, compared
 * word by word as unsigned integers (the first word most significant): a block of
 * records sorted in local memory, and a tile of a merge pass. The kernels that call
 * them (sort.cl, and ccd/contacts.cl, which makes its records and writes them out in
 * the same launches) pass `block`, the records a group sorts, a power of two, and that
 * many records' words of local memory. Record counts stay below 2^31 (the host checks),
 * so no position below overflows.
 *
 * A work-item reads a record whole into private memory before it compares it, so that
 * its words' loads are issued together. In local memory records lie word-major (word w
 * of record i at w * block + i): neighbouring work-items then read neighbouring words,
 * where record-major rows of eight words put eight work-items on one bank. */
#include "common.h"

#ifndef CS_SORT_WORDS
#error "CS_SORT_WORDS: the record's length in words"
#endif

typedef struct {
  uint w[CS_SORT_WORDS];
} cs_record;

/* a goes after b. */
inline bool cs_record_after(const cs_record* a, const cs_record* b)
{
  for (uint w = 0; w < CS_SORT_WORDS; ++w)
    if (a->w[w] != b->w[w]) return a->w[w] > b->w[w];
  return false;
}

/* Records of all ones stand past the end of a block: they sort last and are not
 * written back; where a real record equals them, the words written back are the same
 * either way. */
inline cs_record cs_record_past_end(void)
{
  cs_record r;
  for (uint w = 0; w < CS_SORT_WORDS; ++w) r.w[w] = 0xffffffffu;
  return r;
}

inline cs_record cs_local_record(__local const uint* tile, const uint rows, const uint i)
{
  cs_record r;
  for (uint w = 0; w < CS_SORT_WORDS; ++w) r.w[w] = tile[w * rows + i];
  return r;
}

inline void cs_store_local_record(__local uint* tile, const uint rows, const uint i, const cs_record* r)
{
  for (uint w = 0; w < CS_SORT_WORDS; ++w) tile[w * rows + i] = r->w[w];
}

/* Sorts the `block` records in local memory with a bitonic network; every work-item of
 * the group calls it, once they are all stored. */
inline void cs_sort_local_block(__local uint* sorting, const uint block)
{
  const uint lid = get_local_id(0);
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint size = 2; size <= block; size *= 2)
    for (uint stride = size / 2; stride > 0; stride /= 2) {
      for (uint p = lid; p < block / 2; p += CS_WG_SIZE) {
        const uint i = 2 * stride * (p / stride) + p % stride;
        const cs_record a = cs_local_record(sorting, block, i), b = cs_local_record(sorting, block, i + stride);
        const bool ascending = (i & size) == 0;
        if (ascending ? cs_record_after(&a, &b) : cs_record_after(&b, &a)) {
          cs_store_local_record(sorting, block, i, &b);
          cs_store_local_record(sorting, block, i + stride, &a);
        }
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
}

/* The merge path of a left run of left_n records and a right run of right_n: of the
 * first d merged records, how many come from the left, searched for two diagonals d at
 * once by the group, each by half its work-items, every one probing one place a step
 * (a search of 2^17 places takes three steps where a binary search waits on seventeen
 * reads in a row). `search` is eight words of the kernel's local memory; search[6 + h]
 * returns the answer for diagonal d[h]. */
inline void cs_merge_path_splits(__global const cs_record* left, const uint left_n, __global const cs_record* right,
                                 const uint right_n, const uint d0, const uint d1, __local uint* search)
{
  __local uint* range = search;
  __local uint* first_true = search + 4;
  const uint lid = get_local_id(0);
  const uint lanes = max(CS_WG_SIZE / 2u, 1u), h = min(lid / lanes, 1u), lane = lid - h * lanes;
  if (lid < 2) {
    const uint d = lid ? d1 : d0;
    range[2 * lid] = d > right_n ? d - right_n : 0;
    range[2 * lid + 1] = min(d, left_n);
    first_true[lid] = lanes;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  /* The answer is the first m in [lo, hi) at which left[m] goes after right[d - m - 1],
   * or hi where there is none; the predicate is false, then true, along m. */
  for (;;) {
    const uint lo = range[2 * h], hi = range[2 * h + 1];
    if (range[0] >= range[1] && range[2] >= range[3]) break;
    const uint d = h ? d1 : d0, size = hi - lo;
    const uint m = lo + (uint)(((ulong)lane * size) / lanes);
    if (lo < hi && lid < 2 * lanes) {
      const cs_record a = left[m], b = right[d - m - 1];
      if (cs_record_after(&a, &b)) atomic_min(&first_true[h], lane);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lane == 0 && lid < 2 * lanes && lo < hi) {
      const uint j = first_true[h];
      range[2 * h] = j == 0 ? lo : lo + (uint)(((ulong)(j - 1) * size) / lanes) + 1;
      range[2 * h + 1] = j == lanes ? hi : lo + (uint)(((ulong)j * size) / lanes);
      first_true[h] = lanes;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid < 2) search[6 + lid] = range[2 * lid];
  barrier(CLK_LOCAL_MEM_FENCE);
}

/* A work-item's share of its group's tile of a merge pass: outputs [o, last) of the
 * tile, which holds na records of the left run, then nb of the right, in local memory;
 * the next output is the left's i-th or the right's j-th. */
typedef struct {
  uint first, total, na, nb, i, j, o, last;
} cs_merge_share;

/* Group g of a merge pass writes records [g * per_tile, (g + 1) * per_tile) of the runs
 * of 2 * width that it merges from neighbouring runs of width in `in`: it finds where
 * its tile starts and ends along the merge path, reads the left and right records
 * between into local memory, and each work-item finds where its `chunk` outputs of the
 * tile start by a merge path search of its own there. A tile lies within one merged
 * run: width is a multiple of per_tile. */
inline cs_merge_share cs_merge_tile(__global const cs_record* in, const uint n, const uint width, const uint per_tile,
                                    __local uint* tile, __local uint* search)
{
  cs_merge_share s;
  const uint lid = get_local_id(0);
  s.first = get_group_id(0) * per_tile;
  const uint pair = 2 * width;
  const uint left = s.first - s.first % pair;
  const uint mid = left + min(width, n - left);
  const uint end = left + min(pair, n - left);
  const uint left_n = mid - left, right_n = end - mid;
  const uint d0 = s.first - left, d1 = min(s.first + per_tile, end) - left;
  cs_merge_path_splits(in + left, left_n, in + mid, right_n, d0, d1, search);
  const uint a0 = search[6], a1 = search[7], b0 = d0 - a0;
  s.na = a1 - a0;
  s.total = d1 - d0;
  s.nb = s.total - s.na;
  for (uint k = lid; k < s.total; k += CS_WG_SIZE) {
    const cs_record r = k < s.na ? in[left + a0 + k] : in[mid + b0 + k - s.na];
    cs_store_local_record(tile, per_tile, k, &r);
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  const uint chunk = (per_tile + CS_WG_SIZE - 1) / CS_WG_SIZE, e = lid * chunk;
  s.o = e;
  s.last = e < s.total ? min(e + chunk, s.total) : e;
  uint lo = e > s.nb ? e - s.nb : 0, hi = min(e, s.na);
  while (lo < hi) {
    const uint m = lo + (hi - lo) / 2;
    const cs_record a = cs_local_record(tile, per_tile, m), b = cs_local_record(tile, per_tile, s.na + e - m - 1);
    if (cs_record_after(&a, &b))
      hi = m;
    else
      lo = m + 1;
  }
  s.i = lo;
  s.j = e - lo;
  return s;
}

/* The share's next output, which goes to place first + o of the merged runs (the caller
 * then steps o). */
inline cs_record cs_next_merged(cs_merge_share* s, __local const uint* tile, const uint per_tile)
{
  /* Past the end of a run, any record of the tile stands in: it is not taken. */
  const cs_record a = cs_local_record(tile, per_tile, min(s->i, s->total - 1)),
                  b = cs_local_record(tile, per_tile, min(s->na + s->j, s->total - 1));
  const bool from_left = s->j >= s->nb || (s->i < s->na && !cs_record_after(&a, &b));
  if (from_left)
    ++s->i;
  else
    ++s->j;
  return from_left ? a : b;
}

#endif
