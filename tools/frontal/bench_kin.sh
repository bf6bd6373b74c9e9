#!/usr/bin/env bash
# Cost of the frontal analysis (issue 38): `gait kin` on one walk seen from the front and from
# the side: the Parkinson's trial's markers projected through a pinhole camera in front of the
# walker (tests/data/frontal/gaitkit_pd_anterior) and onto the side view
# (tests/data/gaitkit_pd), the same 671 frames at 150 Hz, alternating, ROUNDS times each;
# prints the medians and their ratio. Both write every CSV and report.html (no PDF, whose
# Chromium start-up would drown the difference).
#
# Usage: tools/frontal/bench_kin.sh [ROUNDS]   (default 7)
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/setup.sh
set +e +o pipefail
rounds=${1:-7}
cargo build -q -p gait-cli
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
front_kp=tests/data/frontal/gaitkit_pd_anterior/keypoints.csv
side_kp=tests/data/gaitkit_pd/keypoints.csv
time_kin() {
  local t0 t1
  t0=$(date +%s.%N)
  target/debug/gait kin --keypoints "$2" --fps 150 --out "$out/$1" --set report.pdf=false >/dev/null 2>&1
  t1=$(date +%s.%N)
  python3 -c "print($t1 - $t0)"
}
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; $(date -u +%F)"
echo "keypoints: $front_kp and $side_kp ($(($(wc -l <"$side_kp") - 3)) frames at 150 Hz)"
front=(); side=()
for r in $(seq "$rounds"); do
  front+=("$(time_kin front "$front_kp")")
  side+=("$(time_kin side "$side_kp")")
done
python3 - "${front[*]}" "${side[*]}" <<'PY'
import statistics, sys
f = [float(x) for x in sys.argv[1].split()]
s = [float(x) for x in sys.argv[2].split()]
mf, ms = statistics.median(f), statistics.median(s)
print(f"gait kin on the front view: median {mf:.3f} s; on the side view: median {ms:.3f} s")
print(f"ratio front / side: {mf / ms:.3f} ({len(f)} rounds each, alternating)")
PY
