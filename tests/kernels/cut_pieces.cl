/* Boxes cut as the conservative solver's late rounds cut them (ccd/conservative.h), for
 * test_narrow_phase: box i (t0, t1, u0, u1, v0, v1) with the spreads of F along t, u and
 * v, `levels` halvings at once; plans[i] is the plan (0: too short to cut so), and
 * pieces[6 (i 2^levels + p) ..] piece p. Built with CS_REAL_DOUBLE. */
#include "ccd/conservative.h"

__kernel void test_cut_pieces(__global const real* boxes, __global const real* spreads, const uint n,
                              const int levels, __global uint* plans, __global real* pieces)
{
  const uint i = get_global_id(0);
  if (i >= n) return;
  __global const real* in = boxes + 6 * i;
  const cs_box b = {in[0], in[1], in[2], in[3], in[4], in[5]};
  const real spread[3] = {spreads[3 * i], spreads[3 * i + 1], spreads[3 * i + 2]};
  const cs_cuts cuts = cs_plan_cuts(b, spread, levels);
  plans[i] = cuts;
  for (uint p = 0; p < cs_pieces(cuts); ++p) {
    const cs_box r = cs_piece(b, cuts, p);
    __global real* out = pieces + 6 * ((i << levels) + p);
    out[0] = r.t0;
    out[1] = r.t1;
    out[2] = r.u0;
    out[3] = r.u1;
    out[4] = r.v0;
    out[5] = r.v1;
  }
}
