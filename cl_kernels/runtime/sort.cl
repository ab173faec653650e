/* Sort of records of `words` 32-bit words, compared word by word as unsigned integers
 * (the first word most significant). Blocks of records are sorted first, each by one
 * work-group in local memory; merge passes then merge neighbouring sorted runs of
 * `width` records into runs of 2 * width. In a merge pass each work-item writes `chunk`
 * consecutive records of one merged run: a binary search along the merge path finds how
 * many of the records before them come from the left run, then it merges sequentially,
 * so a pass costs time linear in n. On equal records the left run's goes first. Record
 * counts stay below 2^31 (the host checks), so no position below overflows. */
#include "common.h"

/* a goes no later than b. */
inline bool cs_record_not_after(__global const uint* a, __global const uint* b, const uint words)
{
  for (uint w = 0; w < words; ++w)
    if (a[w] != b[w]) return a[w] < b[w];
  return true;
}

/* a goes after b. */
inline bool cs_local_record_after(__local const uint* a, __local const uint* b, const uint words)
{
  for (uint w = 0; w < words; ++w)
    if (a[w] != b[w]) return a[w] > b[w];
  return false;
}

/* Each group sorts `block` records (a power of two) from first = group * block, in
 * place, with a bitonic network in local memory. Positions past n hold records of all
 * ones, which sort last and are not written back; where a real record equals them, the
 * words written back are the same either way. */
CS_GROUP_KERNEL void cs_sort_blocks(__global uint* records, const uint n, const uint words, const uint block,
                                    __local uint* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  __global uint* mine = records + (size_t)first * words;
  for (uint k = lid; k < block * words; k += CS_WG_SIZE) sorting[k] = first + k / words < n ? mine[k] : 0xffffffffu;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint size = 2; size <= block; size *= 2)
    for (uint stride = size / 2; stride > 0; stride /= 2) {
      for (uint p = lid; p < block / 2; p += CS_WG_SIZE) {
        const uint i = 2 * stride * (p / stride) + p % stride;
        __local uint* a = sorting + i * words;
        __local uint* b = a + stride * words;
        const bool ascending = (i & size) == 0;
        if (ascending ? cs_local_record_after(a, b, words) : cs_local_record_after(b, a, words))
          for (uint w = 0; w < words; ++w) {
            const uint t = a[w];
            a[w] = b[w];
            b[w] = t;
          }
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
  for (uint k = lid; k < block * words; k += CS_WG_SIZE)
    if (first + k / words < n) mine[k] = sorting[k];
}

inline __global const uint* cs_record(__global const uint* records, const uint i, const uint words)
{
  return records + (size_t)i * words;
}

__kernel void cs_merge_runs(__global const uint* in, __global uint* out, const uint n, const uint words,
                            const uint width, const uint chunk)
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
    if (cs_record_not_after(cs_record(in, left + m, words), cs_record(in, mid + before - m - 1, words), words))
      lo = m + 1;
    else
      hi = m;
  }

  uint i = lo, j = before - lo;
  const uint last = min(first + chunk, end);
  for (uint o = first; o < last; ++o) {
    const bool from_left =
        j >= right_n ||
        (i < left_n && cs_record_not_after(cs_record(in, left + i, words), cs_record(in, mid + j, words), words));
    __global const uint* r = from_left ? cs_record(in, left + i++, words) : cs_record(in, mid + j++, words);
    for (uint w = 0; w < words; ++w) out[(size_t)o * words + w] = r[w];
  }
}
