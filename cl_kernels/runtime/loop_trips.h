#ifndef CSTREAMS_RUNTIME_LOOP_TRIPS_H
#define CSTREAMS_RUNTIME_LOOP_TRIPS_H
/* Mesa's llvmpipe (rusticl, Clover) ends a work-item's loops, silently, once they have
 * made 65535 trips in all; every loop after that stops after its first trip. The runtime
 * probes for such a limit (probe.cl) and builds every program with CS_LOOP_TRIPS set to
 * it (0: no limit). Kernels whose loops run as long as their input asks count their
 * trips against it, and check this canary at their end: a loop of `trips` >= 2 trips
 * that ran fewer says that the work-item's loops were cut short. `trips` must be a
 * value the compiler cannot know and each trip reads `one` (1) through a volatile
 * pointer, so that the loop can be neither unrolled nor folded away. */
inline int cs_loops_were_cut(const uint trips, volatile __global const uint* one)
{
  uint ran = 0;
  for (uint i = 0; i < trips; ++i) ran += *one;
  return ran != trips;
}

#endif
