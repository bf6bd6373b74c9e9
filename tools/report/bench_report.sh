#!/usr/bin/env bash
# Cost of the report step of `gait run` on the whole sample video: exports,
# overlay.mp4, report.html and report.pdf, as run.json's report.seconds
# records them, against the reference for the overlay: a plain ffmpeg
# transcode of the same video with the same encoder settings (decode +
# libx264 veryfast, no drawing), timed in the same round.
#
# Usage: tools/report/bench_report.sh [ROUNDS]   (default 3)
# The first `gait run` fills the cache, so the rounds time the report step
# only (the poses come from the cache).
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh
set +e +o pipefail
rounds=${1:-3}
cargo build -q -p gait-cli
target/debug/gait models fetch blazepose >/dev/null
video=data/sample/sports2d-demo.mp4
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() { target/debug/gait run --no-progress --input "$video" --out "$out/run" --set report.pdf=true "$@" 2>/dev/null; }
run >/dev/null
frames=$(($(wc -l <"$out/run/keypoints.csv") - 3))
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; $(date -u +%F)"
echo "frames analysed: $frames"
for r in $(seq "$rounds"); do
  run
  read -r exports overlay report pdf < <(python3 -c "import json,sys;s=json.load(open('$out/run/run.json'))['report']['seconds'];print(s['exports'],s['overlay'],s['report'],s['pdf'])")
  t0=$(python3 -c "import time; print(time.time())")
  ffmpeg -v error -y -i "$video" -an -c:v libx264 -preset veryfast -pix_fmt yuv420p "$out/plain.mp4"
  plain=$(python3 -c "import time; print(time.time() - $t0)")
  python3 - "$frames" "$exports" "$overlay" "$report" "$pdf" "$plain" <<'PY'
import sys
n, exports, overlay, report, pdf, plain = int(sys.argv[1]), *map(float, sys.argv[2:])
print(f"round: report.html {report:.2f} s, exports {exports:.2f} s, pdf {pdf:.2f} s, "
      f"overlay {overlay:.2f} s ({n/overlay:.1f} fps), plain ffmpeg transcode {plain:.2f} s "
      f"({n/plain:.1f} fps), overlay / plain {overlay/plain:.2f}")
PY
done
