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
    calls, walls, inside = 21, [], []
    for _ in range(calls):
        begin = time.perf_counter()
        ccd.toi(V0, V1)
        walls.append((time.perf_counter() - begin) * 1e3)
        inside.append(ccd.stats["host_ms"])  # the detector's step alone, as C++ times it
    print(f"device    {context.device['name']}")
    print(f"mesh      {start}: {len(V0)} vertices, {len(F)} faces")
    print(f"earliest  t = {toi:.9g}" if toi < 1 else "earliest  none: the step is free of collisions")
    print(f"step size {ccd.collision_free_stepsize(V0, V1):.9g}")
    print(f"contacts  {len(detector.contacts())}")
    median = lambda values: sorted(values)[len(values) // 2]
    print(f"time      {median(walls):.3f} ms per toi call (median of {calls} warm calls), "
          f"{median(inside):.3f} ms of it in the detector's step")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(*sys.argv[1:4])
