#!/usr/bin/env python3
"""CPU benchmark: one guided denoising step (ControlNet + UNet, batch 2) at SD 1.5
size, diffusers/torch vs our candle code, with the same random weights, in one run.

Needs: torch==2.15.0 diffusers==0.42.1 safetensors (Python 3.11), and a release build of
the example: CARGO_TARGET_DIR=... cargo build --release -p gait-diffuse --example bench_step
Run:   python tools/diffuse/bench_step.py --bin $CARGO_TARGET_DIR/release/examples/bench_step
Prints seconds per step for each and the ratio, and each process's peak RSS.
"""

import argparse
import os
import resource
import subprocess
import tempfile
import time

import torch
from diffusers import ControlNetModel, UNet2DConditionModel


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    work = tempfile.mkdtemp(prefix="gait-bench-")
    # SD 1.5 UNet (cross_attention_dim 768, the rest diffusers' defaults = SD 1.5)
    # and sd-controlnet-canny's ControlNet, random weights.
    unet = UNet2DConditionModel(cross_attention_dim=768).eval()
    cn = ControlNetModel(cross_attention_dim=768).eval()
    with torch.no_grad():
        for p in cn.parameters():  # zero convs would make the ControlNet trivial
            p.normal_(0, 0.02)
    unet.save_pretrained(os.path.join(work, "sd", "unet"))
    cn.save_pretrained(os.path.join(work, "cn"))
    lat = args.size // 8
    x = torch.randn(2, 4, lat, lat)
    ctx = torch.randn(2, 77, 768)
    cond = torch.rand(2, 3, args.size, args.size)
    times = []
    with torch.no_grad():
        for i in range(args.repeats):
            t0 = time.perf_counter()
            down, mid = cn(x, 501, encoder_hidden_states=ctx, controlnet_cond=cond, return_dict=False)
            unet(x, 501, encoder_hidden_states=ctx, down_block_additional_residuals=down, mid_block_additional_residual=mid)
            times.append(time.perf_counter() - t0)
            print(f"diffusers step {i}: {times[-1]:.3f} s", flush=True)
    torch_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    del unet, cn
    out = subprocess.run(
        [args.bin, os.path.join(work, "sd"), os.path.join(work, "cn"), str(args.size), str(args.repeats)],
        capture_output=True, text=True, check=True,
    ).stdout
    print(out, end="")
    candle = [float(l.split(":")[1].split()[0]) for l in out.splitlines() if l.startswith("candle step")]
    candle_peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    best_t, best_c = min(times), min(candle)
    print(f"size {args.size}, threads {args.threads}: diffusers {best_t:.2f} s, candle {best_c:.2f} s, "
          f"candle/diffusers time ratio {best_c / best_t:.2f}; peak RSS diffusers {torch_peak:.0f} MiB, candle {candle_peak:.0f} MiB")


if __name__ == "__main__":
    main()
