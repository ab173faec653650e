#!/usr/bin/env python3
"""Runs `cstreams run` over the five real steps of scenes/benchmarks (each step repeated, the
first run a warm-up) in every front mode, and prints one markdown table of medians:
per-step wall time, device time, where the device time goes, memory and counts.

  tools/bench_pipeline.py [--cstreams build/bin/cstreams] [--data scenes/benchmarks]
                          [--device FILTER] [--repeat 11] [--out DIR] [--modes none,exact,deferred]
                          [--front-budget MB] [--solver conservative|cubic]
"""
import argparse
import json
import os
import subprocess
import sys

STEPS = [
    ("cloth-funnel", "227.ply", "228.ply"),
    ("rod-twist", "3036.ply", "3037.ply"),
    ("armadillo-rollers", "326.ply", "327.ply"),
    ("n-body-simulation", "balls16_18.ply", "balls16_19.ply"),
    ("cloth-ball", "cloth_ball92.ply", "cloth_ball93.ply"),
]

# Passes grouped as the table reports them.
GROUPS = [
    ("bounds+refit", lambda n: n.endswith("bounds") or n.startswith("refit")),
    ("front", lambda n: n in ("front update", "search from seeds")),
    ("decompose+orphans", lambda n: n == "decompose" or n.startswith("cull")),
    ("tests", lambda n: n.startswith("test ")),
    ("other", lambda n: True),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cstreams", default="build/bin/cstreams")
    ap.add_argument("--data", default="scenes/benchmarks")
    ap.add_argument("--device", default="")
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--out", default="bench-out")
    ap.add_argument("--modes", default="none,exact,deferred")
    ap.add_argument("--front-budget", default="4")
    ap.add_argument("--solver", default="conservative")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    print("| scene | faces | front | step ms | device ms | bounds+refit | front | decompose+orphans | tests | other "
          "| front pairs | MiB | tri pairs | vf+ee cand | contacts |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, f0, f1 in STEPS:
        frames = os.path.join(args.data, "scalable-ccd-sample", scene, "frames")
        for mode in args.modes.split(","):
            out = os.path.join(args.out, f"{scene}-{mode}-{args.solver}.json")
            cmd = [args.cstreams, "run", os.path.join(frames, f0), os.path.join(frames, f1), "--front", mode,
                   "--front-budget", args.front_budget, "--solver", args.solver, "--repeat", str(args.repeat),
                   "--json", out]
            if args.device:
                cmd += ["--device", args.device]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            with open(out) as f:
                r = json.load(f)
            s = r["steps"][0]
            group_ms = dict((g, 0.0) for g, _ in GROUPS)
            for name, p in s["passes"].items():
                for g, match in GROUPS:
                    if match(name):
                        group_ms[g] += p["ms"]
                        break
            print(f"| {scene} | {r['faces']} | {mode} | {r['median_host_ms']:.3f} | {r['median_device_ms']:.3f} | "
                  + " | ".join(f"{group_ms[g]:.3f}" for g, _ in GROUPS)
                  + f" | {s['front_pairs']} | {s['device_bytes'] / 2**20:.0f} | {s['triangle_pairs']} | "
                  f"{s['vf_candidates'] + s['ee_candidates']} | {s['contacts']} |", flush=True)
    print(f"\ndevice: {r['device']} ({r['platform']}); solver {r['solver']} ({r['precision']}), "
          f"{args.repeat} runs per step, medians after a warm-up", file=sys.stderr)


if __name__ == "__main__":
    main()
