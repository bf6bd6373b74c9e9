#!/usr/bin/env bash
# Per-frame regeneration on this CPU (issues 20 and 30): diffusers' StableDiffusionControlNetPipeline
# and our regenerator (examples/regen_bench), each at the paper's settings (`paper`: 20 UniPC steps,
# CFG and the ControlNet on every step), at configs/zero-shot-fast.toml's (`fast`) and at
# configs/zero-shot-cpu.toml's (`cpu`: fast's keys plus DeepCache, token merging, the subject crop
# and init = "previous"), on the same random SD 1.5-size weights and canny maps of the sample, f32,
# all threads, interleaved in one run. Prints the markdown for BENCHMARKS.md (also $WORK/bench.md)
# with the CPU's model and flags.
#
#   cargo build -p gait-diffuse --example regen_bench
#   PYTHON=/path/to/venv/bin/python tools/diffuse/bench_regen_cpu.sh
#
# The cpu setting: crop_size = [W, H] resizes each square edge map to H x H and crops it to its
# middle W columns (both sides run at W x H: the subject crop's cost, not the subject pass's); init = "previous" runs FRAMES frames one at a time on consecutive maps, the first from
# noise and each later one from the one before's latents at `strength`, and both sides report the
# first frame (first_s) and the median of the later ones (median_s) apart.
#
# The venv needs torch==2.15.0 diffusers==0.42.1 transformers==5.23.0 safetensors
# opencv-python-headless (as tools/diffuse/make_cutoff_fixtures.py), and for the cpu setting
# deepcache==0.1.1 tomesd==0.1.3. Env: BIN (folder of regen_bench, default target/debug/examples),
# WORK (weights and results, default /tmp/gait-cpu-regen, with TINY /tmp/gait-cpu-regen-tiny; the ~5 GB of weights are kept for the
# next run), ROUNDS (1), FRAMES (timed frames per process; default 1, and 3 for a setting with
# init = "previous": the first and 2 steady), SETTINGS ("fast cpu"; any of paper fast cpu),
# SAMPLE_RUN (a run.json of the sample with [selection] mode = "poor": its regenerated frames and
# their runs of consecutive frames give the whole-video estimate), IMPLS ("diffusers ours"; one of
# them alone runs that side only), TINY=1 (a dry run on the tests' tiny configs at 128x128, in
# a WORK of its own: proves the script, times nothing).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
python=${PYTHON:-python3}
bin=${BIN:-$root/target/debug/examples}
work=${WORK:-/tmp/gait-cpu-regen${TINY:+-tiny}}
rounds=${ROUNDS:-1}
settings=${SETTINGS:-fast cpu}
impls=${IMPLS:-diffusers ours}
for s in $settings; do
    case $s in paper | fast | cpu) ;; *) echo "SETTINGS: unknown setting '$s' (paper, fast, cpu)" >&2; exit 2 ;; esac
done
for i in $impls; do
    case $i in diffusers | ours) ;; *) echo "IMPLS: unknown '$i' (diffusers, ours)" >&2; exit 2 ;; esac
done
if [[ " $impls " == *" ours "* && ! -x "$bin/regen_bench" ]]; then
    echo "$bin/regen_bench is missing: build it first (cargo build -p gait-diffuse --example regen_bench)," >&2
    echo "or set BIN to its folder, or IMPLS=diffusers to time diffusers only" >&2
    exit 2
fi
mkdir -p "$work"
size=512 tiny=
# TINY: 128 px maps, so that the cpu setting's crop (W * 128 / H = 64 columns) is still a width our
# regenerator takes (crop sides are multiples of 64).
if [ -n "${TINY:-}" ]; then size=128 tiny=--tiny; fi
if [ ! -f "$work/sd/unet/diffusion_pytorch_model.safetensors" ]; then
    $python "$root/tools/gpu/bench_diffusers.py" prepare "$work" --frames 1 --size "$size" $tiny
fi
# The maps' size as prepared (a WORK of an earlier run keeps its own).
size=$($python -c 'import glob, sys; from PIL import Image; print(Image.open(sorted(glob.glob(sys.argv[1]))[0]).height)' \
    "$work/edges/*.png")
declare -A steps=([paper]=20) sched=([paper]=unipc) gend=([paper]=1.0) cs=([paper]=0.0) ce=([paper]=1.0)
declare -A ci=([paper]=1) cb=([paper]=0) tm=([paper]=0.0) init=([paper]=noise) strength=([paper]=1.0)
declare -A width=([paper]=0) height=([paper]=0)
# The presets' regenerator keys, from the TOMLs themselves (crop_size = [W, H]: the maps resized to
# H x H and cropped to their middle W columns; on maps smaller than H (TINY), W * size / H columns of
# the maps as they are).
keys=$($python - "$root/configs/zero-shot-fast.toml" "$root/configs/zero-shot-cpu.toml" "$size" <<'PY'
import shlex, sys, tomllib
size = int(sys.argv[3])
for setting, path in (("fast", sys.argv[1]), ("cpu", sys.argv[2])):
    r = tomllib.load(open(path, "rb"))["regenerator"]
    keys = dict(steps=r["steps"], sched=r["scheduler"], gend=r.get("guidance_end", 1.0),
                cs=r.get("control_guidance_start", 0.0), ce=r.get("control_guidance_end", 1.0),
                ci=r.get("cache_interval", 1), cb=r.get("cache_branch", 0),
                tm=r.get("token_merge_ratio", 0.0), init=r.get("init", "noise"),
                strength=r.get("strength", 1.0), width=0, height=0)
    if r.get("region", "frame") == "subject":
        w, h = r["crop_size"]
        if size >= h:
            keys["width"], keys["height"] = w, h
        else:
            keys["width"] = w * size // h
            if keys["width"] % 8 or w * size % h:
                sys.exit(f"{path}: crop_size {w}x{h} at height {size} is not a width in multiples of 8")
    for k, v in keys.items():
        print(f"{k}[{setting}]={shlex.quote(str(v))}")
PY
)
eval "$keys"

results=$work/results.jsonl
rm -f "$work/max_rss_kb.txt"
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
flags=$(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -xE 'avx2|fma|avx512f|avx512_bf16|amx_tile|neon|asimd' | tr '\n' ' ')
printf '{"date": "%s", "cpu": "%s", "flags": "%s", "threads": %s, "rounds": %s, "tiny": %s}\n' \
    "$(date -u +%Y-%m-%d)" "$cpu" "${flags% }" "$(nproc)" "$rounds" "$([ -n "$tiny" ] && echo true || echo false)" \
    > "$results"
# Both sides read the weights from the page cache.
cat "$work"/sd/*/*.safetensors "$work"/controlnet/*.safetensors > /dev/null

# Per setting: the timed frames, and the speed-up keys for each side (none for paper and fast, whose
# presets have none).
declare -A frames pyargs ourargs
for s in $settings; do
    if [ "${init[$s]}" = previous ]; then
        frames[$s]=${FRAMES:-3}
        if [ "${frames[$s]}" -lt 2 ]; then
            echo "FRAMES=${frames[$s]}: the $s setting (init = \"previous\") needs 2 or more" >&2
            exit 2
        fi
    else
        frames[$s]=${FRAMES:-1}
    fi
    pyargs[$s]= ourargs[$s]=
    if [ "$s" = cpu ]; then
        pyargs[$s]="--cache-interval ${ci[$s]} --cache-branch ${cb[$s]} --token-merge-ratio ${tm[$s]}"
        pyargs[$s]+=" --width ${width[$s]} --height ${height[$s]} --init ${init[$s]} --strength ${strength[$s]}"
        ourargs[$s]="cache_interval=${ci[$s]} cache_branch=${cb[$s]} token_merge_ratio=${tm[$s]}"
        ourargs[$s]+=" init=${init[$s]} strength=${strength[$s]}"
        if [ "${width[$s]}" != 0 ]; then ourargs[$s]+=" width=${width[$s]} height=${height[$s]}"; fi
    fi
done

for _ in $(seq "$rounds"); do
    for s in $settings; do
        if [[ " $impls " == *" diffusers "* ]]; then
            echo "== diffusers, $s settings" >&2
            # shellcheck disable=SC2086 # pyargs holds separate options
            /usr/bin/time -f "diffusers $s %M" -a -o "$work/max_rss_kb.txt" \
            $python "$root/tools/gpu/bench_diffusers.py" diffusers "$work" "$work/edges" --device cpu --dtype f32 \
                --steps "${steps[$s]}" --scheduler "${sched[$s]}" --guidance-end "${gend[$s]}" \
                --control-start "${cs[$s]}" --control-end "${ce[$s]}" --frames "${frames[$s]}" --warmup 0 \
                ${pyargs[$s]} | grep '^{' | sed "s/^{/{\"setting\": \"$s\", /" | tee -a "$results"
        fi
        if [[ " $impls " == *" ours "* ]]; then
            echo "== ours, $s settings" >&2
            # shellcheck disable=SC2086 # ourargs holds separate key=value arguments
            /usr/bin/time -f "ours $s %M" -a -o "$work/max_rss_kb.txt" \
            "$bin/regen_bench" "$work/sd" "$work/controlnet" "$work/edges" device=cpu dtype=f32 \
                steps="${steps[$s]}" scheduler="${sched[$s]}" guidance_end="${gend[$s]}" \
                control_guidance_start="${cs[$s]}" control_guidance_end="${ce[$s]}" frames="${frames[$s]}" \
                warmup=0 ${ourargs[$s]} | grep '^{' | sed "s/^{/{\"setting\": \"$s\", /" | tee -a "$results"
        fi
    done
done
$python "$root/tools/diffuse/regen_cpu_report.py" "$results" ${SAMPLE_RUN:+"$SAMPLE_RUN"} | tee "$work/bench.md"
# Peak resident memory of each process (GNU time's %M, KiB), for BENCHMARKS.md.
echo "peak RSS (KiB) per process:" | tee -a "$work/bench.md"
tee -a "$work/bench.md" < "$work/max_rss_kb.txt"
