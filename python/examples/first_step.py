"""A real step's two frames through the array API: the earliest time of impact, the
collision-free step size, the contact count and the time per call.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/first_step.py A.ply B.ply [device]
"""
import sys
import time

import cstreams


def main(start, end, device=None):
    context = cstreams.Context(device)
    V0, F = cstreams.read_mesh(start)
    V1, _ = cstreams.read_mesh(end)
    ccd = cstreams.MeshCcd(context, V0, F)
    detector = cstreams.Detector(context, [dict(name="mesh", faces=F, positions=V0)])
    detector.set_positions(0, V1)
    detector.detect()
    toi = ccd.toi(V0, V1)  # the first call builds the front; the timed ones are warm
    calls = 21
    begin = time.perf_counter()
    for _ in range(calls):
        ccd.toi(V0, V1)
    per_call = (time.perf_counter() - begin) / calls * 1e3
    print(f"device    {context.device['name']}")
    print(f"mesh      {start}: {len(V0)} vertices, {len(F)} faces")
    print(f"earliest  t = {toi:.9g}" if toi < 1 else "earliest  none: the step is free of collisions")
    print(f"step size {ccd.collision_free_stepsize(V0, V1):.9g}")
    print(f"contacts  {len(detector.contacts())}")
    print(f"time      {per_call:.3f} ms per toi call (mean of {calls} warm calls)")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(*sys.argv[1:4])
