#!/usr/bin/env bash
# The README's main command: set-up on a fresh machine, then the default
# pipeline on the bundled sample video (the walking part, frames 100-229).
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/setup.sh
cargo build --release -p gait-cli
target/release/gait models fetch blazepose
target/release/gait run --input data/sample/sports2d-demo.mp4 --out runs/sample \
  --set input.first_frame=100 "$@"
echo "results in runs/sample (keypoints.csv, angles.csv, cycles.csv, report.html, run.json)"
