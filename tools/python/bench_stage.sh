#!/usr/bin/env bash
# Issue 31's costs of Python in gait, each against its reference in the same run:
# - a Python pose stage's overhead per 1080p frame beyond the stage's own time (a stage that
#   returns a constant: examples/python/constant_pose.py), target <= 1 ms;
# - `import gait` against `import json` (the interpreter's own start), target <= 0.3 s.
# Usage: tools/python/bench_stage.sh   (the wheel installed in $VENV)
set -euo pipefail
cd "$(dirname "$0")/../.."
VENV=${VENV:-target/python-venv}
cargo build -q -p gait-python --example stage_overhead
for _ in 1 2 3; do
    VIRTUAL_ENV=$(realpath "$VENV") PYTHONPATH=examples/python target/debug/examples/stage_overhead 1920 1080 2000
done
"$VENV/bin/python" - <<'PY'
import statistics, subprocess, sys, time
def start(code):
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True)
    return time.perf_counter() - t
pairs = [(start("import json"), start("import gait")) for _ in range(10)]
base = statistics.median(p[0] for p in pairs)
gait = statistics.median(p[1] for p in pairs)
print(f"python -c 'import json' {base:.3f} s, python -c 'import gait' {gait:.3f} s: import gait costs {gait - base:.3f} s")
PY
