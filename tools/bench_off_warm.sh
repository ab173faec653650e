#!/usr/bin/env bash
# Steps off the warm path (BENCHMARKS.md §2): for each of the five real steps, the warm
# step's wall (exact front, conservative and cubic), the step searched from fixed seeds
# (--front none: wall, and the search's device time) and the cold first step of a fresh
# detector (wall, the median of seven processes, with the median time to make the
# detector, and its front update's device time and launches). One line a step. Wall times are --no-profile. Writes every run's JSON and
# contacts under OUT (default bench-out), so that two builds' contacts compare with cmp.
#   [STEPS="cloth-funnel:227:228 ..."] tools/bench_off_warm.sh [CSTREAMS] [OUT]
set -euo pipefail
cstreams=${1:-build/bin/cstreams}
out=${2:-bench-out}
data=scenes/benchmarks/scalable-ccd-sample
mkdir -p "$out"
# Runs cstreams with the arguments after the first, unprofiled, and prints the fields
# of its JSON report that the first names (comma-separated), joined by ":".
report() { local fields=$1; shift
  "$cstreams" run "$@" --no-profile --json "$out/run.json" >/dev/null
  python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(':'.join(str(j[f]) for f in sys.argv[2].split(',')))" \
    "$out/run.json" "$fields"; }
wall() { report median_host_ms "$@"; }
# A cold run's wall time and the time to make its detector, as "wall:setup".
cold() { report median_host_ms,detector_ms "$@"; }
steps=${STEPS:-cloth-funnel:227:228 rod-twist:3036:3037 armadillo-rollers:326:327 \
n-body-simulation:balls16_18:balls16_19 cloth-ball:cloth_ball92:cloth_ball93}
for step in $steps; do
  IFS=: read -r scene a b <<<"$step"
  frames=("$data/$scene/frames/$a.ply" "$data/$scene/frames/$b.ply")
  warm=$(wall "${frames[@]}" --front exact --repeat 41)
  cubic=$(wall "${frames[@]}" --front exact --solver cubic --repeat 41)
  none=$(wall "${frames[@]}" --front none --repeat 21)
  cold=()
  for _ in 1 2 3 4 5 6 7; do cold+=("$(cold "${frames[@]}" --front exact)"); done
  "$cstreams" run "${frames[@]}" --front none --repeat 11 --json "$out/$scene-none.json" \
    --out "$out/$scene-none.csv" >/dev/null
  "$cstreams" run "${frames[@]}" --front exact --json "$out/$scene-cold.json" --out "$out/$scene-exact.csv" >/dev/null
  python3 - "$out" "$scene" "$warm" "$cubic" "$none" "${cold[@]}" <<'PY'
import json, statistics, sys
out, scene, warm, cubic, none = sys.argv[1:6]
cold = statistics.median(float(c.split(":")[0]) for c in sys.argv[6:])
setup = statistics.median(float(c.split(":")[1]) for c in sys.argv[6:])
search = json.load(open(f"{out}/{scene}-none.json"))["steps"][0]["passes"]["search from seeds"]
update = json.load(open(f"{out}/{scene}-cold.json"))["steps"][0]["passes"]["front update"]
ms = lambda p: float("nan") if p["ms"] is None else p["ms"]
print(f"{scene:18s} warm {float(warm):7.3f}  cubic {float(cubic):7.3f}  none {float(none):7.3f} "
      f"(search {ms(search):7.3f})  cold {cold:7.3f} (front update {ms(update):7.3f}, {update['launches']} launches; "
      f"setup {setup:.1f})")
PY
done
