#!/usr/bin/env bash
# `gait review` on the whole sample video: the recompute after a correction and a frame request,
# each against its command-line reference timed in the same round:
#   - recompute: POST /api/corrections (recompute + atomic save) against `gait kin --corrections`
#     on the same keypoints and file (a process that reads the CSV, recomputes and writes the
#     outputs; report and PDF off);
#   - frame: GET /api/frame/N of a frame already decoded (served from memory) against ffmpeg
#     extracting that one frame as a JPEG (seek, decode, encode).
# The browser test (tests/review.rs) measures the same from the page, redraw included.
#
# Usage: tools/review/bench_review.sh [ROUNDS]   (default 3)
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh
set +e +o pipefail
rounds=${1:-3}
cargo build -q -p gait-cli
target/debug/gait models fetch blazepose >/dev/null
video=data/sample/sports2d-demo.mp4
out=$(mktemp -d)
trap 'kill $server 2>/dev/null; rm -rf "$out"' EXIT
target/debug/gait run --no-progress --input "$video" --out "$out/run" --set report.overlay=false --set report.pdf=false 2>/dev/null
target/debug/gait review "$out/run" >"$out/url" 2>/dev/null &
server=$!
while [ ! -s "$out/url" ]; do sleep 0.2; done
url=$(head -1 "$out/url")
base=${url%%/\?*}
token=${url##*token=}
sleep 15 # let the background decoder finish the whole video
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; $(date -u +%F)"
now() { python3 -c "import time; print(time.time())"; }
body='{"swap":[{"first":120,"last":131}],"event":[{"side":"right","kind":"heel_strike","frame":60,"action":"add"}]}'
printf '| round | review recompute (ms) | gait kin (ms) | ratio | review frame (ms) | ffmpeg frame (ms) | ratio |\n| --- | --- | --- | --- | --- | --- | --- |\n'
for r in $(seq "$rounds"); do
  post=$(curl -s -o /dev/null -w '%{time_total}' -X POST -H 'Content-Type: application/json' -d "$body" "$base/api/corrections?token=$token")
  t0=$(now)
  target/debug/gait kin --keypoints "$out/run/keypoints.csv" --fps 30 --config "$out/run/run.json" \
    --corrections "$out/run/corrections.toml" --out "$out/kin" --set 'kinematics.frame_size=[1768, 994]' \
    --set report.pdf=false --set 'export.formats=[]' >/dev/null 2>&1
  kin=$(python3 -c "print($(now) - $t0)")
  frame=$(curl -s -o /dev/null -w '%{time_total}' "$base/api/frame/150?token=$token")
  t0=$(now)
  ffmpeg -v error -nostdin -ss 5 -i "$video" -frames:v 1 -f image2pipe -c:v mjpeg - >/dev/null
  ff=$(python3 -c "print($(now) - $t0)")
  python3 -c "p,k,f,g=$post,$kin,$frame,$ff; print(f'| $r | {p*1e3:.0f} | {k*1e3:.0f} | {p/k:.2f} | {f*1e3:.1f} | {g*1e3:.0f} | {f/g:.3f} |')"
done
