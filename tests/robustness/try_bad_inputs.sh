#!/usr/bin/env bash
# Feeds the cstreams command line bad input of every kind and classifies what happens:
# a clear error (exit 1, one line "cstreams: ..." naming the file, option or object), a
# crash (killed by a signal), a hang (over 60 s), or a silent run (exit 0). Prints a
# Markdown table and the counts; exits non-zero unless every case is a clear error.
# Usage: tests/robustness/try_bad_inputs.sh [build/bin/cstreams]
set -uo pipefail
cd "$(dirname "$0")/../.."
cli=${1:-build/bin/cstreams}
data=scenes/benchmarks/scalable-ccd-sample/cloth-funnel/frames
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Bad files, each made from a good one.
good=$data/227.ply
head -c 20000 "$good" > "$work/truncated.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n' > "$work/huge.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n' > "$work/nan.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 1 0\n0 1 0\n3 0 1 7\n' > "$work/index.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 1 0\n0 1 0\n3 0 1 1\n' > "$work/degenerate.ply"
head -c 4096 /dev/urandom > "$work/garbage.ply"
cp "$work/garbage.ply" "$work/garbage.obj"
printf 'v 0 0 0\nv 1 0 0\nf 1 2 3\n' > "$work/index.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > "$work/triangle.obj"
mkdir -p "$work/folder.ply"
ln -s /dev/zero "$work/zero.ply"
printf '{"objects": [' > "$work/cut.json"
printf '{"objects": []}' > "$work/empty.json"
printf '{"objects": [{"name": "a", "kind": "liquid", "frames": ["%s"]}]}' "$PWD/$good" > "$work/kind.json"
printf '{"objects": [{"name": "a", "frames": {"pattern": "x%%d.ply", "count": 99999999999}}]}' > "$work/count.json"
printf '{"objects": [{"name": "a", "frames": ["%s", "%s"]}]}' "$PWD/$good" "$work/triangle.obj" > "$work/mismatch.json"
row='0,1,0,1,0,1,1'
{ printf '1,3,0,1,0,1,1\n'; for i in 1 2 3 4 5 6 7; do echo "$row"; done; } > "$work/third.csv"
{ printf '1,0,0,1,0,1,1\n'; for i in 1 2 3 4 5 6 7; do echo "$row"; done; } > "$work/zero.csv"
{ printf '1.5,1,0,1,0,1,1\n'; for i in 1 2 3 4 5 6 7; do echo "$row"; done; } > "$work/fraction.csv"
{ for i in 1 2 3; do echo "$row"; done; } > "$work/cut.csv"
{ printf '0,1,0,1,0,1,2\n'; for i in 1 2 3 4 5 6 7; do echo "$row"; done; } > "$work/truth.csv"

cases=(
  "truncated PLY|run $work/truncated.ply"
  "PLY claiming 2e9 vertices|run $work/huge.ply"
  "NaN coordinate|run $work/nan.ply"
  "face index out of range (PLY)|run $work/index.ply"
  "face index out of range (OBJ)|run $work/index.obj"
  "degenerate triangle|run $work/degenerate.ply"
  "random bytes as PLY|run $work/garbage.ply"
  "random bytes as OBJ|run $work/garbage.obj"
  "folder given as a mesh|run $work/folder.ply"
  "device file given as a mesh|run $work/zero.ply"
  "missing mesh|run $work/missing.ply"
  "frames with different vertex counts|run $good $work/triangle.obj"
  "manifest cut short|run $work/cut.json"
  "manifest without objects|run $work/empty.json"
  "unknown object kind|run $work/kind.json"
  "frame pattern with 1e11 frames|run $work/count.json"
  "manifest frames that disagree|run $work/mismatch.json"
  "query 1/3 (not a double)|accuracy --queries $work/third.csv"
  "query zero denominator|accuracy --queries $work/zero.csv"
  "query non-integer|accuracy --queries $work/fraction.csv"
  "query file cut mid-query|accuracy --queries $work/cut.csv"
  "query truth column 2|accuracy --queries $work/truth.csv"
  "--tolerance -1|run $good --tolerance -1"
  "--tolerance nan|run $good --tolerance nan"
  "--tolerance inf|run $good --tolerance inf"
  "--min-separation -1|run $good --min-separation -1"
  "--max-iterations 0|run $good --max-iterations 0"
  "--max-iterations -1|run $good --max-iterations -1"
  "--front-budget 0|run $good --front deferred --front-budget 0"
  "--repeat 0|run $good --repeat 0"
  "--frames 3abc|run $good --frames 3abc"
  "--frames 5:99|run $data/227.ply $data/228.ply --frames 5:99"
  "unknown solver|run $good --solver fast"
  "unknown registration|run $good --registration lock-sree"
  "--out into a missing folder|run $good --out /nonexistent/dir/c.csv"
  "--json onto a folder|run $good --json $work"
  "--plot into a missing folder|accuracy --plot /nonexistent/p.png"
  "accuracy --tolerance nan|accuracy --tolerance nan"
  "reference --frames x|reference $good --frames x"
  "generate --resolution 1e5|generate cloth-sphere --out $work/g --resolution 100000"
  "unknown device|run $good --device no-such-device"
)

clear=0 crash=0 hang=0 silent=0
echo "| input or fault | exit | outcome | message |"
echo "|---|---|---|---|"
for c in "${cases[@]}"; do
  name=${c%%|*}
  read -r -a args <<< "${c#*|}"
  out=$(timeout 60 "$cli" "${args[@]}" 2>&1 >/dev/null)
  status=$?
  message=$(printf '%s' "$out" | head -n 1 | sed "s|$work/||g; s/|/\\\\|/g")
  if [ $status -eq 124 ]; then outcome=hang; hang=$((hang + 1))
  elif [ $status -gt 128 ]; then outcome=crash; crash=$((crash + 1))
  elif [ $status -eq 0 ]; then outcome="silent run"; silent=$((silent + 1))
  else outcome="clear error"; clear=$((clear + 1))
  fi
  echo "| $name | $status | $outcome | ${message:0:110} |"
done
echo
echo "tried ${#cases[@]}: clear error $clear, crash $crash, hang $hang, silent run $silent"
[ $((crash + hang + silent)) -eq 0 ]
