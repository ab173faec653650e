#ifndef CSTREAMS_RUNTIME_GROUP_SUM_H
#define CSTREAMS_RUNTIME_GROUP_SUM_H
/* The sum of values[0, first) over the work-group of CS_WG_SIZE work-items, in every
 * work-item: each adds up a stride of them, then the group reduces the partial sums in
 * `scratch` (CS_WG_SIZE words of local memory). Every work-item of the group calls it;
 * it ends with a barrier, so scratch may be used again. */
inline uint cs_group_sum_before(__global const uint* values, const uint first, __local uint* scratch)
{
  const uint lid = get_local_id(0);
  uint sum = 0;
  for (uint i = lid; i < first; i += CS_WG_SIZE) sum += values[i];
  scratch[lid] = sum;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = 1u; stride < CS_WG_SIZE; stride *= 2u) {
    if (lid % (2u * stride) == 0u && lid + stride < CS_WG_SIZE) scratch[lid] += scratch[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  const uint total = scratch[0];
  barrier(CLK_LOCAL_MEM_FENCE);
  return total;
}

#endif
