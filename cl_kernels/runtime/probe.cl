/* Built once per context, before the other programs: the work-items per group that a
 * kernel with local memory and barriers may run on this device
 * (CL_KERNEL_WORK_GROUP_SIZE). Some implementations (rusticl on llvmpipe: 32) allow
 * fewer than their CL_DEVICE_MAX_WORK_GROUP_SIZE; CS_WG_SIZE is chosen within it. */
__kernel void cs_probe_work_group(__global uint* data)
{
  __local uint tile[256];
  const uint lid = (uint)get_local_id(0);
  tile[lid & 255u] = data[get_global_id(0)];
  barrier(CLK_LOCAL_MEM_FENCE);
  data[get_global_id(0)] = tile[(lid + 1u) & 255u];
}

/* Counts `n` trips of a loop (count[1] and count[2] hold 1, so that no compiler can
 * fold the loop away). Mesa's llvmpipe (rusticl, Clover) ends every kernel's loops
 * after 65535 trips in all, silently; a device that returns less than `n` here would
 * cut the solvers' searches short without a word. */
__kernel void cs_probe_loop_trips(__global uint* count, const uint n)
{
  uint trips = 0;
  for (uint i = 0; i < n; ++i) trips += count[1u + (i & 1u)];
  count[0] = trips;
}
