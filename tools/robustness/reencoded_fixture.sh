#!/usr/bin/env bash
# Makes tests/data/sample-reencoded/<cpu>/: the keypoints that `gait run` with the default config
# gives on this machine for the bundled sample, for its H.264 CRF 18 copy (the re-encode of
# tests/robustness.rs), and for a 720p CRF 23 copy and an HEVC copy of its mirror, canonical
# columns only. The pose model's floats differ between CPUs'
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
# Two copies as a user's tools make them (ffmpeg's default preset): 720p at CRF 23, and the mirror
# (a right view) in HEVC at CRF 26 as a phone stores it.
ffmpeg -v error -y -i data/sample/sports2d-demo.mp4 -an -vf scale=-2:720 -c:v libx264 -crf 23 \
    "$work/p720_crf23.mp4"
ffmpeg -v error -y -i data/sample/sports2d-demo.mp4 -an -vf hflip -c:v libx265 -crf 26 \
    -tag:v hvc1 -x265-params log-level=error "$work/mirror_hevc.mov"
for v in original crf18 p720_crf23 mirror_hevc; do
    src=data/sample/sports2d-demo.mp4
    [ "$v" = crf18 ] && src=$work/crf18.mp4
    [ "$v" = p720_crf23 ] && src=$work/p720_crf23.mp4
    [ "$v" = mirror_hevc ] && src=$work/mirror_hevc.mov
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
