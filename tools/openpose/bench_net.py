#!/usr/bin/env python3
"""Per-frame time of the COCO-18 OpenPose network: controlnet_aux's torch model vs gait-pose on candle, one
368x368 input, synthetic weights, same run.

Needs: the venv of make_net_fixtures.py (torch, controlnet-aux==0.0.10).
Run from the repository root:
    cargo build --release -p gait-pose --example openpose_net_bench
    python tools/openpose/bench_net.py [ROUNDS]
Prints a Markdown table row. Torch uses its default intra-op threads (all cores), candle its default too.
"""
import os
import subprocess
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import synthetic_weights as sw  # noqa: E402
from export_onnx import checkpoint_key, coco18_model  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))


def torch_ms(rounds):
    model = coco18_model()
    sd = {k: torch.from_numpy(sw.tensor(i, checkpoint_key(k), list(v.shape)))
          for i, (k, v) in enumerate(model.state_dict().items())}
    model.load_state_dict(sd)
    h = w = 368
    x = ((np.arange(3 * h * w) * 7919) % 256).astype(np.float32) / 256 - 0.5
    x = torch.from_numpy(x.reshape(1, 3, h, w))
    with torch.no_grad():
        model(x)
        t = time.perf_counter()
        for _ in range(rounds):
            model(x)
    return (time.perf_counter() - t) * 1000 / rounds


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    t_torch = torch_ms(rounds)
    exe = os.path.join(TARGET, "release", "examples", "openpose_net_bench")
    out = subprocess.run([exe, str(rounds)], check=True, capture_output=True, text=True).stdout
    t_candle = float(out.split()[1])
    print(f"torch {torch.__version__} threads={torch.get_num_threads()}", file=sys.stderr)
    print("| input | torch (controlnet_aux) ms/frame | candle ms/frame | candle / torch |")
    print("|---|---|---|---|")
    print(f"| 1x3x368x368 | {t_torch:.0f} | {t_candle:.0f} | {t_candle / t_torch:.2f} |")


if __name__ == "__main__":
    main()
