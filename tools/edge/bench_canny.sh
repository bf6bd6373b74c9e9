#!/usr/bin/env bash
# Times gait-edge's Canny against cv2.Canny (single-threaded) on the same 1280x720 real frame, in the
# same run, and writes the result into BENCHMARKS.md (section "Canny (gait-edge)").
#
# Needs: ffmpeg, cargo, and a Python with `opencv-python-headless==4.12.0.88 numpy`
# (PYTHON=/path/to/python, default python3). Run from anywhere:
#     PYTHON=/work/venvs/edge/bin/python tools/edge/bench_canny.sh [ITERATIONS]
# Video: GAIT_SAMPLE_VIDEO (default /work/shared/data/sports2d-demo.mp4, Sports2D, BSD-3-Clause).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
PYTHON="${PYTHON:-python3}"
ITER="${1:-50}"
VIDEO="${GAIT_SAMPLE_VIDEO:-/work/shared/data/sports2d-demo.mp4}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT

# Frame 170 (a person walking), scaled to 1280x720 with area averaging.
ffmpeg -v error -i "$VIDEO" -vf "select=eq(n\,170),scale=1280:720:flags=area" -frames:v 1 "$WORK/frame.png"

CV_OUT="$("$PYTHON" - "$WORK" "$ITER" <<'PY'
import sys, time
import cv2, numpy as np
work, iters = sys.argv[1], int(sys.argv[2])
cv2.setNumThreads(1)
rgb = cv2.cvtColor(cv2.imread(f"{work}/frame.png"), cv2.COLOR_BGR2RGB)
gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
cv2.imwrite(f"{work}/gray.png", gray)
def median_ms(img):
    cv2.Canny(img, 100, 200)
    t = []
    for _ in range(iters):
        s = time.perf_counter(); cv2.Canny(img, 100, 200); t.append((time.perf_counter() - s) * 1e3)
    return float(np.median(t))
cv2.imwrite(f"{work}/cv_rgb.png", cv2.Canny(rgb, 100, 200))
cv2.imwrite(f"{work}/cv_gray.png", cv2.Canny(gray, 100, 200))
print(f"cv_rgb_ms={median_ms(rgb):.3f} cv_gray_ms={median_ms(gray):.3f} opencv={cv2.__version__} "
      f"threads={cv2.getNumThreads()} ipp={cv2.ipp.useIPP()}")
PY
)"
echo "$CV_OUT"

cd "$ROOT"
cargo build --release -q -p gait-edge --example canny_bench
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/examples/canny_bench"
OURS="$("$BIN" "$WORK/frame.png" "$WORK/gray.png" "$ITER" "$WORK/cv_rgb.png" "$WORK/cv_gray.png")"
echo "$OURS"

val() { sed -n "s/.*\b$1=\([^ ]*\).*/\1/p" <<<"$2"; }
CV_RGB=$(val cv_rgb_ms "$CV_OUT"); CV_GRAY=$(val cv_gray_ms "$CV_OUT")
RGB=$(val rgb_ms "$OURS"); GRAY=$(val gray_ms "$OURS")
RATIO_RGB=$(awk -v a="$RGB" -v b="$CV_RGB" 'BEGIN{printf "%.2f", a/b}')
RATIO_GRAY=$(awk -v a="$GRAY" -v b="$CV_GRAY" 'BEGIN{printf "%.2f", a/b}')

SECTION="$WORK/section.md"
cat > "$SECTION" <<MD
## Canny (gait-edge)

$(date +%F), $(nproc)-core $(uname -m) machine, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs).
Command: \`PYTHON=/path/to/python tools/edge/bench_canny.sh $ITER\` (median of $ITER runs each, after a warm-up;
frame 170 of sports2d-demo.mp4 scaled to 1280x720; thresholds 100/200, L1).
OpenCV: $(val opencv "$CV_OUT"), \`cv2.setNumThreads(1)\` (threads=$(val threads "$CV_OUT"), IPP=$(val ipp "$CV_OUT");
with one thread OpenCV hands gray input to IPP's Canny, RGB input runs OpenCV's own SIMD code).

| input | gait-edge (ms) | cv2.Canny 1 thread (ms) | ratio (ours / OpenCV) | F1 vs OpenCV |
|---|---|---|---|---|
| RGB 1280x720 | $RGB | $CV_RGB | $RATIO_RGB | $(val f1_rgb "$OURS") |
| gray 1280x720 | $GRAY | $CV_GRAY | $RATIO_GRAY | $(val f1_gray "$OURS") |

MD

# Replace our section (from its heading to the next "## " heading) or append it.
BENCH="$ROOT/BENCHMARKS.md"
touch "$BENCH"
"$PYTHON" - "$BENCH" "$SECTION" <<'PY'
import re, sys
bench, section = sys.argv[1], open(sys.argv[2]).read().rstrip("\n") + "\n\n"
text = open(bench).read()
if not text.strip():
    text = "# Benchmarks\n\n"
pat = re.compile(r"^## Canny \(gait-edge\)\n.*?(?=^## |\Z)", re.S | re.M)
text = pat.sub(lambda _: section, text) if pat.search(text) else text.rstrip("\n") + "\n\n" + section
open(bench, "w").write(text)
PY
cat "$SECTION"
