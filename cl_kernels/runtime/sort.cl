/* Sort of records of CS_SORT_WORDS 32-bit words (sort.h): blocks of `block` records are
 * sorted first, each by one work-group in local memory; merge passes then merge
 * neighbouring sorted runs of `width` records into runs of 2 * width, a tile of
 * `per_tile` records of the merged run per work-group. On equal records the left run's
 * goes first. */
#include "sort.h"

/* Each group sorts `block` records from first = group * block, in place. */
CS_GROUP_KERNEL void cs_sort_blocks(__global cs_record* records, const uint n, const uint block,
                                    __local uint* sorting)
{
  const uint first = get_group_id(0) * block, lid = get_local_id(0);
  __global cs_record* mine = records + first;
  const cs_record past_end = cs_record_past_end();
  for (uint k = lid; k < block; k += CS_WG_SIZE) {
    const cs_record r = first + k < n ? mine[k] : past_end;
    cs_store_local_record(sorting, block, k, &r);
  }
  cs_sort_local_block(sorting, block);
  for (uint k = lid; k < block; k += CS_WG_SIZE)
    if (first + k < n) mine[k] = cs_local_record(sorting, block, k);
}

CS_GROUP_KERNEL void cs_merge_runs(__global const cs_record* in, __global cs_record* out, const uint n,
                                   const uint width, const uint per_tile, __local uint* tile)
{
  __local uint search[8];
  cs_merge_share s = cs_merge_tile(in, n, width, per_tile, tile, search);
  for (; s.o < s.last; ++s.o) out[s.first + s.o] = cs_next_merged(&s, tile, per_tile);
}
