#!/usr/bin/env python3
"""Per-frame time of BlazePose: mediapipe's Python solution vs gait-pose (candle, ort), same frames, one run.

Needs: Python 3.11 with mediapipe==0.10.14 opencv-contrib-python==4.10.0.84; the models fetched into
MODELS_DIR (`gait models fetch blazepose`); ORT_DYLIB_PATH set for the ort run.
Run from the repository root:
    cargo build --release -p gait-pose --example blazepose_bench
    python tools/blazepose/bench.py MODELS_DIR [REPEATS]
Static-image mode on every frame (detector + landmark model), the fixture frames in
crates/gait-pose/tests/fixtures/blazepose. Prints a Markdown table.
"""
import glob
import os
import statistics
import subprocess
import sys
import time

import cv2
import mediapipe as mp

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
FRAMES = sorted(glob.glob(os.path.join(ROOT, "crates/gait-pose/tests/fixtures/blazepose/*.png")))


def mediapipe_ms(pose, imgs, rounds: int) -> float:
    t = time.perf_counter()
    for _ in range(rounds):
        for im in imgs:
            pose.process(im)
    return (time.perf_counter() - t) * 1000 / (rounds * len(imgs))


def ours_ms(models: str, backend: str, rounds: int) -> float:
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    exe = os.path.join(target, os.environ.get("BENCH_PROFILE_DIR", "release"), "examples", "blazepose_bench")
    out = subprocess.run([exe, models, backend, str(rounds)] + FRAMES, check=True, capture_output=True, text=True)
    return float(out.stdout.strip())


def main() -> None:
    models = sys.argv[1]
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    imgs = [cv2.cvtColor(cv2.imread(f), cv2.COLOR_BGR2RGB) for f in FRAMES]
    names = ["mediapipe 0.10.14 (Python, TFLite+XNNPACK)", "gait-pose candle", "gait-pose ort"]
    times = {n: [] for n in names}
    # The machine is shared and noisy: interleave the three so that every
    # repeat compares them under the same load, and report medians.
    with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1) as pose:
        pose.process(imgs[0])
        for _ in range(repeats):
            times[names[0]].append(mediapipe_ms(pose, imgs, 2))
            times[names[1]].append(ours_ms(models, "candle", 2))
            times[names[2]].append(ours_ms(models, "ort", 2))
    ref = times[names[0]]
    print(f"{len(FRAMES)} frames x 2 rounds x {repeats} interleaved repeats, static mode\n")
    print("| implementation | median ms / frame | median ratio to mediapipe (per repeat) |")
    print("|---|---|---|")
    for n in names:
        ratios = [t / r for t, r in zip(times[n], ref)]
        print(f"| {n} | {statistics.median(times[n]):.1f} | {statistics.median(ratios):.2f} |")


if __name__ == "__main__":
    main()
