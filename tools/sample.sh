#!/usr/bin/env bash
# The README's main command: set-up on a fresh machine, then the default
# pipeline on the whole bundled sample video (the subject pass finds the walker
# and her walking bouts; no frame range is needed).
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/setup.sh
# The dev profile builds dependencies and our numeric crates at opt-level 3
# (Cargo.toml), so it is fast and shares its build with tools/test.sh.
cargo build -p gait-cli
target/debug/gait models fetch blazepose
target/debug/gait run --input data/sample/sports2d-demo.mp4 --out runs/sample "$@"
echo "results in runs/sample (report.html, report.pdf, overlay.mp4, keypoints.csv, angles.csv, cycles.csv, keypoints.c3d, run.json)"
