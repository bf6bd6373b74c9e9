#!/usr/bin/env bash
# The GPU benchmark of issue 10, in one command on the GPU machine (tools/gpu/README.md):
#  1. random SD 1.5-size weights in diffusers layout (seed 0) and canny edge maps of the sample;
#  2. per-frame time of diffusers' StableDiffusionControlNetPipeline and of our regenerator
#     (examples/regen_bench) on the same weights and edge maps: 512x512, 20 UniPC steps,
#     guidance 7.5, fp16; the two interleaved over ROUNDS rounds; ours also batched;
#  3. `gait run` end to end on 300 frames with [selection] mode = "poor" (wall clock);
#  4. the markdown for BENCHMARKS.md (also in $OUT/bench.md when $OUT is set).
#
#   tools/gpu/bench_regen.sh            # on the GPU machine, binaries from .gpu/bin
#   tools/gpu/bench_regen.sh --dry-run  # anywhere: CPU, f32, the tests' tiny models, 2 steps,
#                                       # 64x64, few frames: proves the logic, times nothing
# Env: BIN (folder of `gait` and `regen_bench`, default .gpu/bin), MODELS (BlazePose models,
# default .gpu/models), WORK (scratch, default /tmp/gait-gpu-bench), ROUNDS (3), FRAMES (8
# timed frames per process), BATCH (our batched run, 4), E2E_FRAMES (300), PYTHON (python3),
# PARTS ("frames e2e": the per-frame comparison, the end-to-end run, or both).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${BIN:-$root/.gpu/bin}
models=${MODELS:-$root/.gpu/models}
work=${WORK:-/tmp/gait-gpu-bench}
python=${PYTHON:-python3}
rounds=${ROUNDS:-3}
frames=${FRAMES:-8}
batch=${BATCH:-4}
e2e_frames=${E2E_FRAMES:-300}
parts=${PARTS:-frames e2e}
device=cuda dtype=f16 steps=20 tiny= size=512
if [ "${1:-}" = --dry-run ]; then
    device=cpu dtype=f32 steps=2 tiny=--tiny size=64
    rounds=${ROUNDS:-2} frames=${FRAMES:-2} batch=${BATCH:-2} e2e_frames=${E2E_FRAMES:-12}
fi
bench="$python $root/tools/gpu/bench_diffusers.py"
rm -rf "$work"
mkdir -p "$work"
results=$work/results.jsonl

# diffusers is not installed on the GPU machines: the carried wheels (.whl, README).
if ! $python -c 'import diffusers' 2>/dev/null; then
    $python -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target "$work/site" "$root"/.whl/*.whl
    export PYTHONPATH=$work/site${PYTHONPATH:+:$PYTHONPATH}
fi
# The carried binaries travel xz-compressed (tools/gpu/README.md).
for exe in gait regen_bench; do
    if [ ! -x "$bin/$exe" ] && [ -f "$bin/$exe.xz" ]; then
        mkdir -p "$work/bin"
        # Python's lzma, since the machine may lack the xz command.
        $python -c 'import lzma, shutil, sys; shutil.copyfileobj(lzma.open(sys.argv[1]), open(sys.argv[2], "wb"))' \
            "$bin/$exe.xz" "$work/bin/$exe"
        chmod +x "$work/bin/$exe"
    fi
done
[ -x "$bin/gait" ] || bin=$work/bin
if [ "$device" = cuda ]; then
    # Our binaries link libcublas/libcublasLt/libcudart/libnvrtc (.so.13) and libcurand
    # (.so.10): torch's CUDA wheels have them, and so may the toolkit.
    libs=$($python - <<'EOF'
import glob, os, site
dirs = []
for sp in site.getsitepackages() + [site.getusersitepackages()]:
    dirs += sorted(glob.glob(os.path.join(sp, "nvidia", "*", "lib")) + glob.glob(os.path.join(sp, "nvidia", "*", "*", "lib")))
dirs += ["/usr/local/cuda/lib64", "/usr/local/cuda/targets/x86_64-linux/lib"]
print(":".join(d for d in dirs if os.path.isdir(d)))
EOF
)
    export LD_LIBRARY_PATH=$libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    gpu=$(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1)
    missing=$(ldd "$bin/regen_bench" | grep 'not found' || true)
    [ -z "$missing" ] || { echo "libraries not found: $missing" >&2; exit 1; }
else
    gpu="none (dry run on $(nproc) CPU cores)"
fi
echo "{\"gpu\": \"$gpu\", \"date\": \"$(date -u +%F)\", \"rounds\": $rounds, \"tiny\": $([ -n "$tiny" ] && echo true || echo false)}" >>"$results"

t=$(date +%s)
$bench prepare "$work" $tiny --frames "$e2e_frames" --size "$size"
echo "weights and frames: $(($(date +%s) - t)) s"

for r in $(seq "$rounds"); do
    [[ $parts == *frames* ]] || break
    echo "round $r/$rounds"
    $bench diffusers "$work" "$work/edges" --device "$device" --dtype "$dtype" --steps "$steps" --frames "$frames" | tee -a "$results"
    for b in 1 "$batch"; do
        "$bin/regen_bench" "$work/sd" "$work/controlnet" "$work/edges" device="$device" dtype="$dtype" \
            steps="$steps" batch="$b" frames="$frames" | tee -a "$results"
    done
done

# End to end: canny -> ControlNet (on the GPU) -> BlazePose (candle, CPU), poor frames only.
if [[ $parts == *e2e* ]]; then
cat >"$work/e2e.toml" <<EOF
[run]
device = "$device"
batch_size = $batch
cache = false
[selection]
mode = "poor"
[edge]
kind = "canny"
[regenerator]
kind = "controlnet"
sd_path = "$work/sd"
controlnet_path = "$work/controlnet"
dtype = "$dtype"
steps = $steps
batch = $batch
EOF
t0=$(date +%s.%N)
"$bin/gait" --models-dir "$models" run --no-progress --config "$work/e2e.toml" --input "$work/frames" --out "$work/e2e"
t1=$(date +%s.%N)
$python - "$work/e2e/run.json" "$t0" "$t1" "$device" "$dtype" "$batch" >>"$results" <<'EOF'
import json, sys
run = json.load(open(sys.argv[1]))
sel = run["selection"]
print(json.dumps({"e2e_s": float(sys.argv[3]) - float(sys.argv[2]), "frames": sel["frames"],
                  "regenerated": sel["regenerated_count"], "width": run["input"]["width"],
                  "height": run["input"]["height"], "device": sys.argv[4], "dtype": sys.argv[5],
                  "batch": int(sys.argv[6]), "stages": run["stages"]}))
EOF
tail -1 "$results"
fi
echo
$bench report "$results" | tee "$work/bench.md"
if [ -n "${OUT:-}" ]; then
    cp "$work/bench.md" "$results" "$OUT/"
    if [ -f "$work/e2e/run.json" ]; then cp "$work/e2e/run.json" "$OUT/"; fi
fi
