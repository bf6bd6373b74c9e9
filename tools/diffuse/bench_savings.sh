#!/usr/bin/env bash
# Each saving of configs/zero-shot-cpu.toml alone on top of configs/zero-shot-fast.toml (issue 30),
# ours only, on the random SD 1.5-size weights and edge maps that bench_regen_cpu.sh prepared in
# WORK, interleaved in one run: fast, fast + subject crop, fast + DeepCache, fast + token merging,
# fast + init = "previous", and the whole cpu preset. Prints a markdown table of seconds per frame
# and the ratio to fast of the same run (for init = "previous": the frames after the first).
#
#   cargo build -p gait-diffuse --example regen_bench
#   PYTHON=/path/to/venv/bin/python tools/diffuse/bench_regen_cpu.sh   # prepares WORK once
#   tools/diffuse/bench_savings.sh
#
# Env: BIN (folder of regen_bench, default target/debug/examples), WORK (default /tmp/gait-cpu-regen),
# FRAMES (timed frames for init = "previous", default 3).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${BIN:-$root/target/debug/examples}
work=${WORK:-/tmp/gait-cpu-regen}
frames=${FRAMES:-3}
if [ ! -x "$bin/regen_bench" ] || [ ! -d "$work/edges" ]; then
    echo "needs $bin/regen_bench and the weights and edge maps of bench_regen_cpu.sh in $work" >&2
    exit 2
fi
# The fast preset's keys and the cpu preset's savings, from the TOMLs themselves.
eval "$(python3 - "$root/configs/zero-shot-fast.toml" "$root/configs/zero-shot-cpu.toml" <<'PY'
import sys, tomllib
f = tomllib.load(open(sys.argv[1], "rb"))["regenerator"]
c = tomllib.load(open(sys.argv[2], "rb"))["regenerator"]
w, h = c["crop_size"]
print(f"fast='steps={f['steps']} scheduler={f['scheduler']} guidance_end={f['guidance_end']} "
      f"control_guidance_start={f['control_guidance_start']} control_guidance_end={f['control_guidance_end']}'")
print(f"crop='width={w} height={h}'")
print(f"cache='cache_interval={c['cache_interval']} cache_branch={c['cache_branch']}'")
print(f"merge='token_merge_ratio={c['token_merge_ratio']}'")
print(f"previous='init={c['init']} strength={c['strength']}'")
PY
)"
previous="$previous frames=$frames"
results=$work/savings.jsonl
: > "$results"
run() {
    local name=$1
    shift
    echo "== ours, $name" >&2
    # shellcheck disable=SC2086 # the settings are separate key=value arguments
    "$bin/regen_bench" "$work/sd" "$work/controlnet" "$work/edges" device=cpu dtype=f32 warmup=0 \
        $fast "$@" | grep '^{' | sed "s/^{/{\"setting\": \"$name\", /" | tee -a "$results"
}
run fast frames=1
run "fast + subject crop" $crop frames=1
run "fast + DeepCache" $cache frames=1
run "fast + token merging" $merge frames=1
run "fast + init previous" $previous
run "cpu (all)" $crop $cache $merge $previous
python3 - "$results" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
base = next(r["median_s"] for r in rows if r["setting"] == "fast")
print(f"| setting (ours, {rows[0]['size']} px tall) | s per frame | first frame s | / fast |")
print("| --- | --- | --- | --- |")
for r in rows:
    first = f"{r['first_s']:.1f}" if r["init"] == "previous" else ""
    print(f"| {r['setting']} | {r['median_s']:.1f} | {first} | {r['median_s'] / base:.3f} |")
PY
