#!/usr/bin/env bash
# Per-frame regeneration on this CPU (issue 20): diffusers' StableDiffusionControlNetPipeline and
# our regenerator (examples/regen_bench), each at the paper's settings (20 UniPC steps, CFG and the
# ControlNet on every step) and at configs/zero-shot-fast.toml's, on the same random SD 1.5-size
# weights and canny maps of the sample, 512x512, f32, all threads, interleaved in one run. Prints
# the markdown for BENCHMARKS.md (also $WORK/bench.md) with the CPU's model and flags.
#
#   cargo build -p gait-diffuse --example regen_bench
#   PYTHON=/path/to/venv/bin/python tools/diffuse/bench_regen_cpu.sh
#
# The venv needs torch==2.15.0 diffusers==0.42.1 transformers==5.23.0 safetensors
# opencv-python-headless (as tools/diffuse/make_cutoff_fixtures.py). Env: BIN (folder of
# regen_bench, default target/debug/examples), WORK (weights and results, default
# /tmp/gait-cpu-regen; the ~5 GB of weights are kept for the next run), ROUNDS (1), FRAMES (timed
# frames per process, 1), SETTINGS ("paper fast"), SAMPLE_RUN (a run.json of the sample with
# [selection] mode = "poor": its regenerated and total frame counts give the whole-video estimate),
# TINY=1 (a dry run on the tests' tiny configs at 64x64: proves the script, times nothing).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
python=${PYTHON:-python3}
bin=${BIN:-$root/target/debug/examples}
work=${WORK:-/tmp/gait-cpu-regen}
rounds=${ROUNDS:-1}
frames=${FRAMES:-1}
settings=${SETTINGS:-paper fast}
mkdir -p "$work"
size=512 tiny=
if [ -n "${TINY:-}" ]; then size=64 tiny=--tiny; fi
if [ ! -f "$work/sd/unet/diffusion_pytorch_model.safetensors" ]; then
    $python "$root/tools/gpu/bench_diffusers.py" prepare "$work" --frames 1 --size "$size" $tiny
fi

# The preset's regenerator keys, from the TOML itself.
read -r fast_steps fast_sched fast_gend fast_cs fast_ce < <($python - "$root/configs/zero-shot-fast.toml" <<'PY'
import sys, tomllib
r = tomllib.load(open(sys.argv[1], "rb"))["regenerator"]
print(r["steps"], r["scheduler"], r.get("guidance_end", 1.0), r.get("control_guidance_start", 0.0),
      r.get("control_guidance_end", 1.0))
PY
)
declare -A steps=([paper]=20 [fast]=$fast_steps) sched=([paper]=unipc [fast]=$fast_sched)
declare -A gend=([paper]=1.0 [fast]=$fast_gend) cs=([paper]=0.0 [fast]=$fast_cs) ce=([paper]=1.0 [fast]=$fast_ce)

results=$work/results.jsonl
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
flags=$(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -xE 'avx2|fma|avx512f|avx512_bf16|amx_tile|neon|asimd' | tr '\n' ' ')
printf '{"date": "%s", "cpu": "%s", "flags": "%s", "threads": %s, "rounds": %s}\n' \
    "$(date -u +%Y-%m-%d)" "$cpu" "${flags% }" "$(nproc)" "$rounds" > "$results"
# Both sides read the weights from the page cache.
cat "$work"/sd/*/*.safetensors "$work"/controlnet/*.safetensors > /dev/null

for _ in $(seq "$rounds"); do
    for s in $settings; do
        echo "== diffusers, $s settings" >&2
        $python "$root/tools/gpu/bench_diffusers.py" diffusers "$work" "$work/edges" --device cpu --dtype f32 \
            --steps "${steps[$s]}" --scheduler "${sched[$s]}" --guidance-end "${gend[$s]}" \
            --control-start "${cs[$s]}" --control-end "${ce[$s]}" --frames "$frames" --warmup 0 \
            | grep '^{' | sed "s/^{/{\"setting\": \"$s\", /" | tee -a "$results"
        echo "== ours, $s settings" >&2
        "$bin/regen_bench" "$work/sd" "$work/controlnet" "$work/edges" device=cpu dtype=f32 \
            steps="${steps[$s]}" scheduler="${sched[$s]}" guidance_end="${gend[$s]}" \
            control_guidance_start="${cs[$s]}" control_guidance_end="${ce[$s]}" frames="$frames" warmup=0 \
            | grep '^{' | sed "s/^{/{\"setting\": \"$s\", /" | tee -a "$results"
    done
done
$python "$root/tools/diffuse/regen_cpu_report.py" "$results" ${SAMPLE_RUN:+"$SAMPLE_RUN"} | tee "$work/bench.md"
