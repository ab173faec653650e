/* Sort of records of CS_SORT_WORDS 32-bit words, compared word by word as unsigned
 * integers (the first word most significant). Blocks of `block` records are sorted
 * first, each by one work-group in local memory; merge passes then merge neighbouring
 * sorted runs of `width` records into runs of 2 * width, a tile of `block` records of
 * the merged run per work-group. On equal records the left run's goes first. Record
 * counts stay below 2^31 (the host checks), so no position below overflows.
 *
 * A work-item reads a record whole into private memory before it compares it, so that
 * its words' loads are issued together. In local memory records lie word-major (word w
 * of record i at w * block + i): neighbouring work-items then read neighbouring words,
 * where record-major rows of eight words put eight work-items on one bank. */
#include "common.h"

#ifndef CS_SORT_WORDS
#error "the host sets CS_SORT_WORDS"
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

/* Each group sorts `block` records (a power of two) from first = group * block, in
 * place, with a bitonic network in local memory. Positions past n hold records of all
 * ones, which sort last and are not written back; where a real record equals them, the
 * words written back are the same either way. */
CS_GROUP_KERNEL void cs_sort_blocks(__global cs_record* records, const uint n, const uint block,
                                    __local uint* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  __global cs_record* mine = records + first;
  cs_record last;
  for (uint w = 0; w < CS_SORT_WORDS; ++w) last.w[w] = 0xffffffffu;
  for (uint k = lid; k < block; k += CS_WG_SIZE) {
    const cs_record r = first + k < n ? mine[k] : last;
    cs_store_local_record(sorting, block, k, &r);
  }
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
  for (uint k = lid; k < block; k += CS_WG_SIZE)
    if (first + k < n) mine[k] = cs_local_record(sorting, block, k);
}

/* The merge path of a left run of left_n records and a right run of right_n: of the
 * first d merged records, how many come from the left, searched for two diagonals d at
 * once by the group, each by half its work-items, every one probing one place a step
 * (a search of 2^17 places takes three steps where a binary search waits on seventeen
 * reads in a row). split[h] returns the answer for diagonal d[h]. */
inline void cs_merge_path_splits(__global const cs_record* left, const uint left_n, __global const cs_record* right,
                                 const uint right_n, const uint d0, const uint d1, __local uint* range,
                                 __local uint* first_true, __local uint* split)
{
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
  if (lid < 2) split[lid] = range[2 * lid];
  barrier(CLK_LOCAL_MEM_FENCE);
}

/* Group g writes records [g * block, (g + 1) * block) of the merged runs: it finds where
 * its tile starts and ends along the merge path, reads the left and right records
 * between into local memory, and each work-item merges `chunk` records of the tile from
 * a merge path search of its own there. A tile lies within one merged run: width is a
 * multiple of block. */
CS_GROUP_KERNEL void cs_merge_runs(__global const cs_record* in, __global cs_record* out, const uint n,
                                   const uint width, const uint block, __local uint* tile)
{
  __local uint range[4], first_true[2], split[2];
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  const uint pair = 2 * width;
  const uint left = first - first % pair;
  const uint mid = left + min(width, n - left);
  const uint end = left + min(pair, n - left);
  const uint left_n = mid - left, right_n = end - mid;
  const uint d0 = first - left, d1 = min(first + block, end) - left;
  cs_merge_path_splits(in + left, left_n, in + mid, right_n, d0, d1, range, first_true, split);
  const uint a0 = split[0], a1 = split[1], b0 = d0 - a0;
  const uint na = a1 - a0, total = d1 - d0, nb = total - na;
  for (uint k = lid; k < total; k += CS_WG_SIZE) {
    const cs_record r = k < na ? in[left + a0 + k] : in[mid + b0 + k - na];
    cs_store_local_record(tile, block, k, &r);
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  const uint chunk = (block + CS_WG_SIZE - 1) / CS_WG_SIZE, e = lid * chunk;
  if (e >= total) return;
  uint lo = e > nb ? e - nb : 0, hi = min(e, na);
  while (lo < hi) {
    const uint m = lo + (hi - lo) / 2;
    const cs_record a = cs_local_record(tile, block, m), b = cs_local_record(tile, block, na + e - m - 1);
    if (cs_record_after(&a, &b))
      hi = m;
    else
      lo = m + 1;
  }
  uint i = lo, j = e - lo;
  const uint last = min(e + chunk, total);
  for (uint o = e; o < last; ++o) {
    /* Past the end of a run, any record of the tile stands in: it is not taken. */
    const cs_record a = cs_local_record(tile, block, min(i, total - 1)),
                    b = cs_local_record(tile, block, min(na + j, total - 1));
    const bool from_left = j >= nb || (i < na && !cs_record_after(&a, &b));
    out[first + o] = from_left ? a : b;
    if (from_left)
      ++i;
    else
      ++j;
  }
}
