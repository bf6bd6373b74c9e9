#!/usr/bin/env bash
# Encode speed of overlay.mp4 against a plain ffmpeg transcode of the same frames.
#
# Usage: tools/report/bench_overlay.sh [FRAMES] [SIZE] [-- extra overlay_bench arguments]
#   FRAMES  frames of the sample video to encode (default 230, the whole video)
#   SIZE    WxH to scale the frames to first (default the video's 1768x994;
#           1920x1080 for the 1080p target of 30 fps on two cores)
# Env: VIDEO (default data/sample/sports2d-demo.mp4), RUN (a run folder whose
# marks are drawn; default runs/sample when it exists, else a synthetic walker),
# PRESET (default veryfast), LAYOUT (skeleton or side-by-side).
# Prints both times, frames per second and their ratio.
set -euo pipefail
cd "$(dirname "$0")/../.."

frames=${1:-230}
size=${2:-}
shift $(( $# > 2 ? 2 : $# ))
[[ ${1:-} == -- ]] && shift

video=${VIDEO:-data/sample/sports2d-demo.mp4}
[[ -f $video ]] || video=/work/shared/data/sports2d-demo.mp4
run=${RUN:-}
[[ -z $run && -f runs/sample/keypoints_filtered.csv ]] && run=runs/sample

args=(--input "$video" --frames "$frames" --preset "${PRESET:-veryfast}" --layout "${LAYOUT:-skeleton}")
[[ -n $size ]] && args+=(--size "$size")
[[ -n $run ]] && args+=(--run "$run")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# Release build: the dev profile compiles this crate at opt-level 1.
cargo run --quiet --release -p gait-overlay --example overlay_bench -- "${args[@]}" --out "$out" "$@"
