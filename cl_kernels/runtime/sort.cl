/* Sort of records of CS_SORT_WORDS 32-bit words, compared word by word as unsigned
 * integers (the first word most significant). Blocks of records are sorted first, each
 * by one work-group in local memory; merge passes then merge neighbouring sorted runs of
 * `width` records into runs of 2 * width. In a merge pass each work-item writes `chunk`
 * consecutive records of one merged run: a binary search along the merge path finds how
 * many of the records before them come from the left run, then it merges sequentially,
 * so a pass costs time linear in n. On equal records the left run's goes first. Record
 * counts stay below 2^31 (the host checks), so no position below overflows.
 *
 * A record is read whole into private memory before it is compared: its words' loads
 * are then issued together, where a comparison reading word after word would wait for
 * each one (a pass is bound by these waits, not by bandwidth). */
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

/* Each group sorts `block` records (a power of two) from first = group * block, in
 * place, with a bitonic network in local memory. Positions past n hold records of all
 * ones, which sort last and are not written back; where a real record equals them, the
 * words written back are the same either way. */
CS_GROUP_KERNEL void cs_sort_blocks(__global cs_record* records, const uint n, const uint block,
                                    __local cs_record* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  __global cs_record* mine = records + first;
  cs_record last;
  for (uint w = 0; w < CS_SORT_WORDS; ++w) last.w[w] = 0xffffffffu;
  for (uint k = lid; k < block; k += CS_WG_SIZE) sorting[k] = first + k < n ? mine[k] : last;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint size = 2; size <= block; size *= 2)
    for (uint stride = size / 2; stride > 0; stride /= 2) {
      for (uint p = lid; p < block / 2; p += CS_WG_SIZE) {
        const uint i = 2 * stride * (p / stride) + p % stride;
        cs_record a = sorting[i], b = sorting[i + stride];
        const bool ascending = (i & size) == 0;
        if (ascending ? cs_record_after(&a, &b) : cs_record_after(&b, &a)) {
          sorting[i] = b;
          sorting[i + stride] = a;
        }
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  for (uint k = lid; k < block; k += CS_WG_SIZE)
    if (first + k < n) mine[k] = sorting[k];
}

__kernel void cs_merge_runs(__global const cs_record* in, __global cs_record* out, const uint n, const uint width,
                            const uint chunk)
{
  const uint first = (uint)get_global_id(0) * chunk;
  if (first >= n) return;
  const uint pair = 2 * width;
  const uint left = first - first % pair;
  const uint mid = left + min(width, n - left);
  const uint end = left + min(pair, n - left);
  const uint left_n = mid - left, right_n = end - mid;
  const uint before = first - left;

  /* Left records among the first `before` of the merged run: the first m at which
   * left[m] would come after right[before - m - 1]. */
  uint lo = before > right_n ? before - right_n : 0, hi = min(before, left_n);
  while (lo < hi) {
    const uint m = lo + (hi - lo) / 2;
    const cs_record a = in[left + m], b = in[mid + before - m - 1];
    if (cs_record_after(&a, &b))
      hi = m;
    else
      lo = m + 1;
  }

  /* The next record of each run stays in private memory until it is written. */
  uint i = lo, j = before - lo;
  cs_record a, b;
  if (i < left_n) a = in[left + i];
  if (j < right_n) b = in[mid + j];
  const uint last = min(first + chunk, end);
  for (uint o = first; o < last; ++o) {
    if (j >= right_n || (i < left_n && !cs_record_after(&a, &b))) {
      out[o] = a;
      if (++i < left_n && o + 1 < last) a = in[left + i];
    } else {
      out[o] = b;
      if (++j < right_n && o + 1 < last) b = in[mid + j];
    }
  }
}
