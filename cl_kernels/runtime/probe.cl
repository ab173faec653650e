/* Built once per context, before the other programs, after runtime/loop_trips.h (the
 * runtime puts that header in front, as it builds this file without its registry).
 *
 * The work-items per group that a kernel with local memory and barriers may run on
 * this device (CL_KERNEL_WORK_GROUP_SIZE). Some implementations (rusticl on llvmpipe:
 * 32) allow fewer than their CL_DEVICE_MAX_WORK_GROUP_SIZE; CS_WG_SIZE is chosen
 * within it. */
__kernel void cs_probe_work_group(__global uint* data)
{
  __local uint tile[256];
  const uint lid = (uint)get_local_id(0);
  tile[lid & 255u] = data[get_global_id(0)];
  barrier(CLK_LOCAL_MEM_FENCE);
  data[get_global_id(0)] = tile[(lid + 1u) & 255u];
}

/* Counts `n` trips of a loop into count[0] (count[1] and count[2] hold 1, so that no
 * compiler can fold the loop away), then whether the canary saw loops cut short into
 * count[3]. A device that returns less than `n` ends loops early (see loop_trips.h). */
__kernel void cs_probe_loop_trips(__global uint* count, const uint n)
{
  uint trips = 0;
  for (uint i = 0; i < n; ++i) trips += count[1u + (i & 1u)];
  count[0] = trips;
  count[3] = (uint)cs_loops_were_cut(2u + (n == 0u), count + 1);
}

/* `n` trips, each a load through a volatile pointer (one[1] holds 1) whose address
 * depends on the last load, so that no compiler may fold, skip or overlap them: twenty
 * thousand take tens of microseconds on any device, which a profiling timer that times
 * kernels must see. */
__kernel void cs_probe_timer(volatile __global const uint* one, const uint n, __global uint* out)
{
  uint sum = 0;
  for (uint i = 0; i < n; ++i) sum += one[1u + (sum >> 31)];
  out[0] = sum;
}
