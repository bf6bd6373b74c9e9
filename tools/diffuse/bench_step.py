#!/usr/bin/env python3
"""CPU benchmark: one guided denoising step (ControlNet + UNet, batch 2) at SD 1.5 size,
diffusers/torch vs our code on candle and on ONNX Runtime, with the same random weights,
in one run.

Needs: torch==2.15.0 diffusers==0.42.1 safetensors onnx==1.23.2 (Python 3.11), the ONNX
Runtime library (ORT_DYLIB_PATH, from the PyPI onnxruntime==1.31.1 wheel) for the ort side,
and a build of the example:
  CARGO_TARGET_DIR=... cargo build -p gait-diffuse --example bench_step
Run:
  ORT_DYLIB_PATH=.../libonnxruntime.so.1.31.1 python tools/diffuse/bench_step.py \
      --bin $CARGO_TARGET_DIR/debug/examples/bench_step [--impls diffusers,ort,candle] [--rounds 2]

The weights are written once (safetensors for candle and diffusers, ONNX with external data for
ort: the UNet is 3.4 GB in f32; about 10 GB of temporary disk in all, removed at the end).
Each implementation then runs in its own process (load, then --repeats steps), the processes
interleaved over --rounds rounds so a changing machine load hits all of them alike. Prints
seconds per step (best and median over all steps) for each, the ratios to diffusers, and each
implementation's peak RSS (the largest over its processes, from wait4).
"""

import argparse
import gc
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def diffusers_worker(work, size, repeats, threads):
    from diffusers import ControlNetModel, UNet2DConditionModel

    torch.set_num_threads(threads)
    unet = UNet2DConditionModel.from_pretrained(os.path.join(work, "sd", "unet")).eval()
    cn = ControlNetModel.from_pretrained(os.path.join(work, "cn")).eval()
    lat = size // 8
    x = torch.randn(2, 4, lat, lat)
    ctx = torch.randn(2, 77, 768)
    cond = torch.rand(2, 3, size, size)
    with torch.no_grad():
        for i in range(repeats):
            t0 = time.perf_counter()
            down, mid = cn(x, 501, encoder_hidden_states=ctx, controlnet_cond=cond, return_dict=False)
            unet(x, 501, encoder_hidden_states=ctx, down_block_additional_residuals=down,
                 mid_block_additional_residual=mid)
            print(f"diffusers step {i}: {time.perf_counter() - t0:.3f} s", flush=True)


def check(work, bin_path, size):
    """Full-size agreement: one guided step of diffusers and of our candle code on the same
    weights and the same random inputs; prints the largest difference of the UNet outputs,
    relative to diffusers' largest magnitude (the fixture tests' measure)."""
    from diffusers import ControlNetModel, UNet2DConditionModel
    from safetensors.torch import load_file, save_file

    g = torch.Generator().manual_seed(1)
    lat = size // 8
    inputs = {
        "x": torch.randn(2, 4, lat, lat, generator=g),
        "ctx": torch.randn(2, 77, 768, generator=g),
        "cond": torch.rand(2, 3, size, size, generator=g),
    }
    in_path, out_path = os.path.join(work, "check_inputs.safetensors"), os.path.join(work, "check_eps.safetensors")
    save_file(inputs, in_path)
    unet = UNet2DConditionModel.from_pretrained(os.path.join(work, "sd", "unet")).eval()
    cn = ControlNetModel.from_pretrained(os.path.join(work, "cn")).eval()
    with torch.no_grad():
        down, mid = cn(inputs["x"], 501, encoder_hidden_states=inputs["ctx"], controlnet_cond=inputs["cond"],
                       return_dict=False)
        want = unet(inputs["x"], 501, encoder_hidden_states=inputs["ctx"], down_block_additional_residuals=down,
                    mid_block_additional_residual=mid).sample
    del unet, cn
    gc.collect()
    subprocess.run([bin_path, "candle", os.path.join(work, "sd"), os.path.join(work, "cn"), str(size), "1",
                    in_path, out_path], check=True)
    got = load_file(out_path)["eps"]
    err = ((got - want).abs().max() / want.abs().max()).item()
    print(f"full-size check: max |candle - diffusers| / max |diffusers| = {err:.3e} "
          f"(max |diffusers| {want.abs().max().item():.3f})")


def prepare(work, onnx):
    """SD 1.5's UNet (cross_attention_dim 768, the rest diffusers' defaults = SD 1.5) and
    sd-controlnet-canny's ControlNet with random weights, as safetensors and (when `onnx`,
    for the ort side) as ONNX."""
    from diffusers import ControlNetModel, UNet2DConditionModel

    import export_onnx

    torch.manual_seed(0)
    unet = UNet2DConditionModel(cross_attention_dim=768).eval()
    cn = ControlNetModel(cross_attention_dim=768).eval()
    with torch.no_grad():
        for p in cn.parameters():  # zero convs would make the ControlNet trivial
            p.normal_(0, 0.02)
    unet.save_pretrained(os.path.join(work, "sd", "unet"))
    cn.save_pretrained(os.path.join(work, "cn"))
    onnx_dir = os.path.join(work, "onnx")
    if not onnx:
        return onnx_dir
    n = export_onnx.export_controlnet(os.path.join(work, "cn"), onnx_dir, "f32", cn)
    export_onnx.export_unet(os.path.join(work, "sd", "unet"), onnx_dir, "f32", n, unet=unet, controlnet=cn)
    del unet, cn
    gc.collect()
    return onnx_dir


def run_child(cmd):
    """Runs `cmd`; returns its step times (s) and its peak RSS (MiB)."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    print(out, end="", flush=True)
    if proc.returncode != 0:
        raise SystemExit(f"{cmd[0]} failed with {proc.returncode}")
    times = [float(l.split(":")[1].split()[0]) for l in out.splitlines() if " step " in l]
    return times, usage.ru_maxrss / 1024


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", help="the bench_step example (needed for candle and ort)")
    ap.add_argument("--impls", default="diffusers,ort,candle")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--repeats", type=int, default=2, help="steps per process")
    ap.add_argument("--rounds", type=int, default=1, help="interleaved processes per implementation")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--work", help="keep the weights in this folder and reuse them on later runs "
                    "(default: a temporary folder, removed at the end)")
    ap.add_argument("--check", action="store_true",
                    help="instead of timing, compare candle's step with diffusers' on the same inputs")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        diffusers_worker(args.worker, args.size, args.repeats, args.threads)
        return
    impls = args.impls.split(",")
    work = args.work or tempfile.mkdtemp(prefix="gait-bench-")
    try:
        t0 = time.perf_counter()
        onnx_dir = os.path.join(work, "onnx")
        ready = os.path.isdir(os.path.join(work, "cn")) and ("ort" not in impls or os.path.isdir(onnx_dir))
        if not ready:
            onnx_dir = prepare(work, "ort" in impls)
            print(f"weights written and exported in {time.perf_counter() - t0:.0f} s", flush=True)
        if args.check:
            check(work, args.bin, args.size)
            return
        cmds = {
            "diffusers": [sys.executable, os.path.abspath(__file__), "--worker", work, "--size", str(args.size),
                          "--repeats", str(args.repeats), "--threads", str(args.threads)],
            "candle": [args.bin, "candle", os.path.join(work, "sd"), os.path.join(work, "cn"), str(args.size),
                       str(args.repeats)],
            "ort": [args.bin, "ort", onnx_dir, str(args.size), str(args.repeats)],
        }
        times = {i: [] for i in impls}
        peaks = {i: 0.0 for i in impls}
        for r in range(args.rounds):
            order = impls if r % 2 == 0 else impls[::-1]
            for impl in order:
                t, peak = run_child(cmds[impl])
                times[impl] += t
                peaks[impl] = max(peaks[impl], peak)
        best = {i: min(times[i]) for i in impls}
        median = {i: statistics.median(times[i]) for i in impls}
        ref = best.get("diffusers")
        print(f"size {args.size}, threads {args.threads}, {args.rounds} round(s) x {args.repeats} steps")
        for i in impls:
            ratio = (f", {i}/diffusers ratio best {best[i] / ref:.2f}, median {median[i] / median['diffusers']:.2f}"
                     if ref and i != "diffusers" else "")
            print(f"{i}: best {best[i]:.2f} s/step, median {median[i]:.2f} (all: {', '.join(f'{x:.1f}' for x in times[i])})"
                  f"{ratio}; peak RSS {peaks[i]:.0f} MiB")
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
