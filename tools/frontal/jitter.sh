#!/usr/bin/env bash
# BlazePose's jitter on the bundled sample, side and front (issue 38): the walker's clean
# stretch in a side view (tests/data/sample-blazepose, frames 127-158), and the man on the box,
# who faces the camera doing jumping jacks in frames 0-95, cropped out and run through the
# default pipeline. The frontal noise model of crates/gait-kin/tests/frontal_mocap.rs takes its
# numbers from what this prints.
#     bash tools/frontal/jitter.sh [WORK]   (WORK: default target/frontal-jitter)
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh >/dev/null
work=${1:-target/frontal-jitter}
mkdir -p "$work"
cargo build -q -p gait-cli
# Lossless, so only the pose model's jitter is measured (x 450-950, y 0-560: the man only).
ffmpeg -loglevel error -y -i ../shared/data/sports2d-demo.mp4 -vf "crop=500:560:450:0" \
    -frames:v 96 -c:v libx264 -crf 0 -pix_fmt yuv444p "$work/man-facing-camera.mp4"
rm -rf "$work/run"
target/debug/gait run --no-progress --input "$work/man-facing-camera.mp4" --out "$work/run" \
    --set report.overlay=false --set report.pdf=false >/dev/null 2>&1 || true
python3 tools/frontal/measure_jitter.py tests/data/sample-blazepose/keypoints.csv 127 158
# Knees and feet, where they stand still: the walker's stances between her manual events.
python3 tools/frontal/measure_stance_jitter.py tests/data/sample-blazepose/keypoints.csv \
    tests/data/sample-events/events.csv
python3 tools/frontal/measure_jitter.py "$work/run/keypoints.csv" 0 95
