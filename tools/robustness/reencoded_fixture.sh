#!/usr/bin/env bash
# Makes tests/data/sample-reencoded/<cpu>/: the keypoints that `gait run` with the default config
# gives on this machine for the bundled sample and for its H.264 CRF 18 copy (the re-encode of
# tests/robustness.rs), canonical columns only. The pose model's floats differ between CPUs'
# kernels, and with them which decisions tip; a folder per CPU lets crates/gait-kin/tests/
# reencoded.rs check the kinematics' decisions on every CPU's keypoints on any machine.
# Usage: bash tools/robustness/reencoded_fixture.sh NAME   (e.g. amd-zen4-avx512)
set -euo pipefail
cd "$(dirname "$0")/../.."
name=${1:?usage: reencoded_fixture.sh NAME (the CPU, e.g. amd-zen4-avx512)}
source tools/setup.sh
cargo build -p gait-cli
target/debug/gait models fetch blazepose
work=target/reencoded-fixture/$name
out=tests/data/sample-reencoded/$name
mkdir -p "$work" "$out"
ffmpeg -v error -y -i data/sample/sports2d-demo.mp4 -an -c:v libx264 -crf 18 -preset veryfast \
    -pix_fmt yuv420p "$work/crf18.mp4"
for v in original crf18; do
    src=data/sample/sports2d-demo.mp4
    [ "$v" = crf18 ] && src=$work/crf18.mp4
    rm -rf "$work/$v"
    target/debug/gait run --input "$src" --out "$work/$v" --set report.overlay=false \
        --set report.pdf=false --set 'export.formats=[]' --no-progress
    # Keep the canonical keypoints (the kinematics' input), drop BlazePose's native bp_* columns.
    python3 - "$work/$v/keypoints.csv" "$out/$v.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
keep = [i for i, part in enumerate(rows[1]) if not part.startswith("bp_")]
with open(sys.argv[2], "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    for r in rows:
        w.writerow([r[i] for i in keep])
PY
done
{
    echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs)"
    echo "flags: $(grep -m1 '^flags' /proc/cpuinfo | grep -o 'avx512f\|avx2\|fma' | sort -u | xargs)"
    echo "backend: $(python3 -c "import json;print(json.load(open('$work/original/run.json'))['config']['pose']['backend'])")"
    echo "made: $(date -u +%Y-%m-%d) by tools/robustness/reencoded_fixture.sh"
} > "$out/machine.txt"
cat "$out/machine.txt"
