#!/usr/bin/env bash
# Cost of the subject pass: the default pipeline on the whole sample video with
# the subject pass (default) and without it (`subject.enabled=false`, the pose
# model picks a person frame by frame, as before), interleaved, cache off.
# Prints each run's wall time and the ratio of the medians.
#   bash tools/subject/bench_subject_pass.sh [rounds]
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh
cargo build -q -p gait-cli
rounds="${1:-3}"
video=data/sample/sports2d-demo.mp4
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
time_run() {
  local start end
  start=$(date +%s.%N)
  target/debug/gait run --no-progress --input "$video" --out "$out/run" --set run.cache=false "$@" >/dev/null 2>&1
  end=$(date +%s.%N)
  awk -v a="$start" -v b="$end" 'BEGIN {printf "%.2f", b - a}'
}
with=(); without=()
for r in $(seq "$rounds"); do
  without+=("$(time_run --set subject.enabled=false)")
  with+=("$(time_run)")
  echo "round $r: without subject pass ${without[-1]} s, with ${with[-1]} s"
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
mw=$(median "${with[@]}"); mo=$(median "${without[@]}")
echo "median: without ${mo} s, with ${mw} s, ratio $(awk -v a="$mw" -v b="$mo" 'BEGIN {printf "%.3f", a / b}')"
grep -m1 "model name" /proc/cpuinfo
