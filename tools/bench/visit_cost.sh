#!/usr/bin/env bash
# Issue 39's cost target: a visit of 4 videos against the 4 runs alone, in turn (ROUNDS rounds).
# The passes: the bundled sample (left), its mirror (right), and both re-encoded at CRF 18
# (there is no real front or back video of the walk). Usage: tools/bench/visit_cost.sh [ROUNDS]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
source tools/setup.sh
gait="${GAIT_BIN:-target/debug/gait}"
work="target/bench/visit"
rm -rf "$work" && mkdir -p "$work"
sample="$root/../shared/data/sports2d-demo.mp4"
ffmpeg -v error -y -i "$sample" -vf hflip -c:v libx264 -crf 12 -preset veryfast -pix_fmt yuv420p "$work/right.mp4"
ffmpeg -v error -y -i "$sample" -c:v libx264 -crf 18 -preset veryfast -pix_fmt yuv420p "$work/left2.mp4"
ffmpeg -v error -y -i "$work/left2.mp4" -vf hflip -c:v libx264 -crf 18 -preset veryfast -pix_fmt yuv420p "$work/right2.mp4"
passes=("$sample" "$work/right.mp4" "$work/left2.mp4" "$work/right2.mp4")
now() { date +%s.%N; }
for round in $(seq "${1:-2}"); do
  rm -rf "$work/runs" "$work/visit"
  t0=$(now)
  for i in "${!passes[@]}"; do
    "$gait" run --input "${passes[$i]}" --out "$work/runs/$i" --no-progress >/dev/null 2>"$work/run-$i.log"
  done
  t1=$(now)
  "$gait" visit --out "$work/visit" --left "${passes[0]}" --right "${passes[1]}" \
    --left "${passes[2]}" --right "${passes[3]}" --no-progress >"$work/visit.log" 2>&1
  t2=$(now)
  python3 -c "import sys; a, b, c = map(float, sys.argv[1:]); print(f'round $round: 4 runs {b - a:.1f} s, the visit {c - b:.1f} s, the visit costs {c - b - (b - a):+.1f} s more')" "$t0" "$t1" "$t2"
  tail -1 "$work/visit.log"
done
