#!/usr/bin/env bash
# gait.run against `gait run` on the same input, interleaved, each into the same folder path
# (the report names the folder) with no cache from before: wall time of each and whether every
# output file is byte-identical (run.json, report.html and report.pdf are compared without the
# command line and the times they record). Issue 31's target: time ratio <= 1.05.
# Usage: tools/python/bench_run.sh [ROUNDS] [INPUT]   (the wheel installed in $VENV)
set -euo pipefail
cd "$(dirname "$0")/../.."
ROUNDS=${1:-3}
INPUT=${2:-../shared/data/sports2d-demo.mp4}
VENV=${VENV:-target/python-venv}
GAIT=${GAIT:-target/debug/gait}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
OUT=$WORK/run
now() { date +%s.%N; }
for r in $(seq 1 "$ROUNDS"); do
    rm -rf "$OUT"
    t0=$(now)
    "$GAIT" run --input "$INPUT" --out "$OUT" --no-progress 2>/dev/null
    t1=$(now)
    rm -rf "$WORK/cli" && mv "$OUT" "$WORK/cli"
    t2=$(now)
    "$VENV/bin/python" -c "import sys, gait; gait.run(sys.argv[1], out=sys.argv[2], progress=False)" "$INPUT" "$OUT"
    t3=$(now)
    rm -rf "$WORK/py" && mv "$OUT" "$WORK/py"
    echo "round $r: gait run $(echo "$t1 - $t0" | bc) s, gait.run $(echo "$t3 - $t2" | bc) s, ratio $(echo "scale=3; ($t3 - $t2) / ($t1 - $t0)" | bc)"
done
"$VENV/bin/python" tools/python/same_outputs.py "$WORK/cli" "$WORK/py"
