#!/usr/bin/env bash
# Times the elementary tests on the five real steps: conservative single and double and
# cubic single, exact front, each step repeated (the first run a warm-up), and prints
# one line per run: scene, solver, precision, median device ms, the tests' share,
# contacts. Writes the JSON of every run under OUT (default bench-out).
#   tools/bench_solvers.sh [CSTREAMS] [OUT] [REPEAT]
set -euo pipefail
cstreams=${1:-build/bin/cstreams}
out=${2:-bench-out}
repeat=${3:-11}
data=scenes/benchmarks/scalable-ccd-sample
mkdir -p "$out"
for step in cloth-funnel:227:228 rod-twist:3036:3037 armadillo-rollers:326:327 \
            n-body-simulation:balls16_18:balls16_19 cloth-ball:cloth_ball92:cloth_ball93; do
  IFS=: read -r scene a b <<<"$step"
  for run in conservative:single conservative:double cubic:single; do
    IFS=: read -r solver precision <<<"$run"
    json="$out/$scene-$solver-$precision.json"
    "$cstreams" run "$data/$scene/frames/$a.ply" "$data/$scene/frames/$b.ply" --front exact --solver "$solver" \
      --precision "$precision" --repeat "$repeat" --json "$json" >/dev/null
    python3 - "$json" "$scene" "$solver" "$precision" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["steps"][0]
tests = sum(p["ms"] for n, p in s["passes"].items() if n.startswith(("test ", "refine ")))
print(f"{sys.argv[2]:18s} {sys.argv[3]:12s} {sys.argv[4]:6s} device {r['median_device_ms']:9.3f} ms  "
      f"wall {r['median_host_ms']:9.3f} ms  tests {tests:9.3f} ms  contacts {s['contacts']}")
PY
  done
done
