"""How near a miss each false contact of the hand-made set is.

For every query that a solver reports but the exact truth says never touches: the
smallest distance of its features over the step (sampled, then refined by ternary
search, in double), relative to the query's largest coordinate as the solver's
tolerance is. Prints the largest per set and solver setting, so that false contacts
can be told from real misses: within a few tolerances, they are near misses.

    PYTHONPATH=build/python /usr/bin/python3 tools/near_misses.py [DEVICE]
"""
import collections
import glob
import sys

import numpy as np

import cstreams

QUERIES = "scenes/benchmarks/sample-queries"
TOLERANCE = 1e-5


def point_triangle(p, a, b, c):
    """Point-triangle distance by the closest point's region (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return np.linalg.norm(p - a)
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return np.linalg.norm(p - b)
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return np.linalg.norm(p - (a + d1 / (d1 - d3) * ab))
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return np.linalg.norm(p - c)
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return np.linalg.norm(p - (a + d2 / (d2 - d6) * ac))
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return np.linalg.norm(p - (b + w * (c - b)))
    v, w = vb / (va + vb + vc), vc / (va + vb + vc)
    return np.linalg.norm(p - (a + ab * v + ac * w))


def segment_segment(p1, q1, p2, q2):
    """Segment-segment distance by clamped closest points (Ericson 5.1.9)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = d1 @ d1, d2 @ d2, d2 @ r
    tiny = 1e-300
    if a <= tiny and e <= tiny:
        return np.linalg.norm(r)
    if a <= tiny:
        s, t = 0.0, np.clip(f / e, 0, 1)
    else:
        c = d1 @ r
        if e <= tiny:
            s, t = np.clip(-c / a, 0, 1), 0.0
        else:
            b = d1 @ d2
            den = a * e - b * b
            s = np.clip((b * f - c * e) / den, 0, 1) if den > tiny else 0.0
            t = (b * s + f) / e
            if t < 0:
                s, t = np.clip(-c / a, 0, 1), 0.0
            elif t > 1:
                s, t = np.clip((b - c) / a, 0, 1), 1.0
    return np.linalg.norm((p1 + d1 * s) - (p2 + d2 * t))


def smallest_distance(q, kind):
    """The features' smallest distance over the step, their points moving linearly."""
    distance = point_triangle if kind == "vf" else segment_segment
    at = lambda t: distance(*[q[i] + t * (q[4 + i] - q[i]) for i in range(4)])
    times = np.linspace(0, 1, 4001)
    sampled = np.array([at(t) for t in times])
    k = int(sampled.argmin())
    lo, hi = times[max(k - 1, 0)], times[min(k + 1, len(times) - 1)]
    for _ in range(60):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        if at(m1) < at(m2):
            hi = m2
        else:
            lo = m1
    return min(sampled.min(), at(0.5 * (lo + hi)))


def main(device):
    context = cstreams.Context(device)
    solvers = {
        "single": cstreams.QuerySolver(context, precision="single"),
        "single, float alone": cstreams.QuerySolver(context, precision="single", escalate=False),
    }
    if context.device["fp64"]:
        solvers["double"] = cstreams.QuerySolver(context, precision="double")
    largest, count = collections.defaultdict(float), collections.Counter()
    for kind, folder in (("vf", "vertex-face"), ("ee", "edge-edge")):
        for path in sorted(glob.glob(f"{QUERIES}/*/{folder}/*.csv")):
            points, truth = cstreams.read_queries(path)
            dataset = path.split("/")[-3]
            for name, solver in solvers.items():
                collides = solver.solve(kind, points)[0]
                for q in points[collides & ~truth]:
                    gap = smallest_distance(q, kind) / np.abs(q).max()
                    largest[name, dataset] = max(largest[name, dataset], gap)
                    count[name, dataset] += 1
    for name in solvers:
        rows = sorted((d, g) for (n, d), g in largest.items() if n == name)
        print(f"{name}: largest gap {max((g for _, g in rows), default=0):.3g} x scale")
        for dataset, gap in rows:
            print(f"  {dataset:32s} FP {count[name, dataset]:4d}  largest gap {gap:.3g} x scale"
                  f" ({gap / TOLERANCE:.3g} tolerances)")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
