"""Time per call and earliest time of impact against the solver's tolerance, on one
step, for both solvers: what a tighter tolerance costs. Writes a PNG.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/plot_tolerance.py A.ply B.ply out.png [device]
"""
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import cstreams  # noqa: E402

TOLERANCES = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6]


def measure(ccd, V0, V1, tolerance, calls=11):
    toi = ccd.toi(V0, V1, tolerance=tolerance)  # a new tolerance builds the detector again
    begin = time.perf_counter()
    for _ in range(calls):
        ccd.toi(V0, V1, tolerance=tolerance)
    return toi, (time.perf_counter() - begin) / calls * 1e3


def main(start, end, out, device=None):
    context = cstreams.Context(device)
    V0, F = cstreams.read_mesh(start)
    V1, _ = cstreams.read_mesh(end)
    figure, (times, tois) = plt.subplots(1, 2, figsize=(10, 4))
    for solver in ("conservative", "cubic"):
        ccd = cstreams.MeshCcd(context, V0, F, solver=solver)
        results = [measure(ccd, V0, V1, t) for t in TOLERANCES]
        times.plot(TOLERANCES, [ms for _, ms in results], marker="o", label=solver)
        tois.plot(TOLERANCES, [toi for toi, _ in results], marker="o", label=solver)
    for axis, label in ((times, "ms per call (warm)"), (tois, "earliest time of impact")):
        axis.set_xscale("log")
        axis.set_xlabel("tolerance (relative)")
        axis.set_ylabel(label)
        axis.legend()
    figure.suptitle(f"{start} on {context.device['name']}")
    figure.tight_layout()
    figure.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(*sys.argv[1:5])
