/* Exclusive prefix sum of uint: cs_scan_reduce sums tiles, and cs_scan_tiles scans
 * each tile starting from its tile's offset, which each group adds up from the tile
 * sums before it where they fit one tile, and which the host otherwise scans the same
 * way first, recursively; or, for a few tiles, in one kernel by one group
 * (cs_scan_in_one_group). A compaction is the scan of its keep flags, whose last
 * launch (cs_compact_tiles, cs_compact_in_one_group) copies each kept item to its place
 * rather than writing the offsets: a launch and the offsets' memory fewer.
 * Work-items cooperate only through local memory and barriers: nothing assumes
 * they run in lockstep, so the same code is right on pocl, NVIDIA and AMD. */
#include "common.h"
#include "copy.h"
#include "group_sum.h"

#ifndef CS_SCAN_ITEMS
#error "CS_SCAN_ITEMS (items per work-item) is chosen by the host's Scan for the device"
#endif
#define CS_SCAN_TILE (CS_WG_SIZE * CS_SCAN_ITEMS)
/* One padding word every 32 keeps a work-item's consecutive items in distinct banks. */
#define CS_PAD(i) ((i) + ((i) >> 5))

/* Returns the exclusive prefix of `value` over the work-group; *total is the group's sum. */
uint cs_group_exclusive_scan(uint value, __local uint* scratch, uint* total)
{
  const uint lid = get_local_id(0);
  scratch[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint offset = 1; offset < CS_WG_SIZE; offset <<= 1) {
    const uint add = lid >= offset ? scratch[lid - offset] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const uint inclusive = scratch[lid];
  *total = scratch[CS_WG_SIZE - 1];
  barrier(CLK_LOCAL_MEM_FENCE);
  return inclusive - value;
}

CS_GROUP_KERNEL void cs_scan_reduce(__global const uint* in, const uint n, __global uint* tile_sums)
{
  __local uint scratch[CS_WG_SIZE];
  const size_t base = get_group_id(0) * (size_t)CS_SCAN_TILE + get_local_id(0);
  uint sum = 0;
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) {
    const size_t i = base + (size_t)k * CS_WG_SIZE;
    if (i < n) sum += in[i];
  }
  uint total;
  cs_group_exclusive_scan(sum, scratch, &total);
  if (get_local_id(0) == 0) tile_sums[get_group_id(0)] = total;
}

/* Scans the tile at `base` of `in` into local memory, starting from `offset`, and
 * returns offset plus the tile's sum; tile[CS_PAD(t)] then holds the offset of item
 * base + t. */
inline uint cs_scan_tile_locally(__global const uint* in, const uint n, const size_t base, const uint offset,
                                 __local uint* tile, __local uint* scratch)
{
  const uint lid = get_local_id(0);
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) {
    const uint t = k * CS_WG_SIZE + lid;
    tile[CS_PAD(t)] = base + t < n ? in[base + t] : 0u;
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  uint sum = 0;
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) sum += tile[CS_PAD(lid * CS_SCAN_ITEMS + k)];
  uint group_total;
  const uint prefix = cs_group_exclusive_scan(sum, scratch, &group_total);
  uint running = offset + prefix;
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) {
    const uint t = CS_PAD(lid * CS_SCAN_ITEMS + k);
    const uint v = tile[t];
    tile[t] = running;
    running += v;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return offset + group_total;
}

/* Scans the tile at `base` starting from `offset` and returns offset plus the tile's sum.
 * `in` and `out` may be the same buffer: the group reads its whole tile before writing
 * it. Ends with a barrier, so the group may go on to another tile. */
inline uint cs_scan_tile(__global const uint* in, const uint n, __global uint* out, const size_t base,
                         const uint offset, __local uint* tile, __local uint* scratch)
{
  const uint end = cs_scan_tile_locally(in, n, base, offset, tile, scratch);
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) {
    const uint t = k * CS_WG_SIZE + get_local_id(0);
    if (base + t < n) out[base + t] = tile[CS_PAD(t)];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return end;
}

/* The same over the keep flags of a compaction, copying each kept item of `src`
 * (items of `words` words) to its place in `dst`, those past `capacity` dropped. */
inline uint cs_compact_tile(__global const uint* keep, const uint n, const size_t base, const uint offset,
                            __global const uint* src, const uint words, __global uint* dst, const uint capacity,
                            __local uint* tile, __local uint* scratch)
{
  const uint end = cs_scan_tile_locally(keep, n, base, offset, tile, scratch);
  for (uint k = 0; k < CS_SCAN_ITEMS; ++k) {
    const uint t = k * CS_WG_SIZE + get_local_id(0);
    const uint o = tile[CS_PAD(t)];
    if (base + t < n && keep[base + t] && o < capacity) cs_copy_item(src, base + t, dst, o, words);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return end;
}

/* The offset of the group's tile: tile_offsets holds each tile's offset, or with
 * `summed` each tile's sum, those before the group's then added up by the group: a
 * launch fewer than scanning them first (4 us on the H100), for a few thousand loads a
 * group. */
inline uint cs_tile_offset(__global const uint* tile_offsets, const uint summed, __local uint* scratch)
{
  const uint g = get_group_id(0);
  return summed ? cs_group_sum_before(tile_offsets, g, scratch) : tile_offsets[g];
}

/* The last group leaves the total in counters[total_slot]. */
inline void cs_tiles_total(__global uint* counters, const uint total_slot, const uint end)
{
  if (total_slot != CS_NO_SLOT && get_local_id(0) == 0 && get_group_id(0) == get_num_groups(0) - 1)
    counters[total_slot] = end;
}

CS_GROUP_KERNEL void cs_scan_tiles(__global const uint* in, const uint n, __global uint* out,
                                   __global const uint* tile_offsets, const uint summed,
                                   __global uint* counters, const uint total_slot)
{
  __local uint tile[CS_PAD(CS_SCAN_TILE)];
  __local uint scratch[CS_WG_SIZE];
  const uint offset = cs_tile_offset(tile_offsets, summed, scratch);
  cs_tiles_total(counters, total_slot,
                 cs_scan_tile(in, n, out, get_group_id(0) * (size_t)CS_SCAN_TILE, offset, tile, scratch));
}

CS_GROUP_KERNEL void cs_compact_tiles(__global const uint* keep, const uint n, __global const uint* src,
                                      const uint words, __global uint* dst, const uint capacity,
                                      __global const uint* tile_offsets, const uint summed,
                                      __global uint* counters, const uint total_slot)
{
  __local uint tile[CS_PAD(CS_SCAN_TILE)];
  __local uint scratch[CS_WG_SIZE];
  const uint offset = cs_tile_offset(tile_offsets, summed, scratch);
  cs_tiles_total(counters, total_slot,
                 cs_compact_tile(keep, n, get_group_id(0) * (size_t)CS_SCAN_TILE, offset, src, words, dst, capacity,
                                 tile, scratch));
}

/* The whole scan by one group, tile after tile, where the input is a few tiles long: one
 * launch where the kernels above take two, each costing its launch and its tail (4-8
 * us each on the H100). */
CS_GROUP_KERNEL void cs_scan_in_one_group(__global const uint* in, const uint n, __global uint* out,
                                          __global uint* counters, const uint total_slot)
{
  __local uint tile[CS_PAD(CS_SCAN_TILE)];
  __local uint scratch[CS_WG_SIZE];
  uint end = 0;
  for (size_t base = 0; base < n; base += CS_SCAN_TILE) end = cs_scan_tile(in, n, out, base, end, tile, scratch);
  if (total_slot != CS_NO_SLOT && get_local_id(0) == 0) counters[total_slot] = end;
}

/* Two scans at once, a group each, tile after tile (Scan::exclusive_both): one launch
 * where two inputs of a few tiles each took two each, as a pass's two outputs' segment
 * counts do. */
CS_GROUP_KERNEL void cs_scan_two_in_a_group_each(__global const uint* in0, const uint n0, __global uint* out0,
                                                 const uint total_slot0, __global const uint* in1, const uint n1,
                                                 __global uint* out1, const uint total_slot1,
                                                 __global uint* counters)
{
  __local uint tile[CS_PAD(CS_SCAN_TILE)];
  __local uint scratch[CS_WG_SIZE];
  const int second = get_group_id(0) == 1;
  __global const uint* in = second ? in1 : in0;
  __global uint* out = second ? out1 : out0;
  const uint n = second ? n1 : n0, total_slot = second ? total_slot1 : total_slot0;
  uint end = 0;
  for (size_t base = 0; base < n; base += CS_SCAN_TILE) end = cs_scan_tile(in, n, out, base, end, tile, scratch);
  if (total_slot != CS_NO_SLOT && get_local_id(0) == 0) counters[total_slot] = end;
}

CS_GROUP_KERNEL void cs_compact_in_one_group(__global const uint* keep, const uint n, __global const uint* src,
                                             const uint words, __global uint* dst, const uint capacity,
                                             __global uint* counters, const uint total_slot)
{
  __local uint tile[CS_PAD(CS_SCAN_TILE)];
  __local uint scratch[CS_WG_SIZE];
  uint end = 0;
  for (size_t base = 0; base < n; base += CS_SCAN_TILE)
    end = cs_compact_tile(keep, n, base, end, src, words, dst, capacity, tile, scratch);
  if (get_local_id(0) == 0) counters[total_slot] = end;
}
