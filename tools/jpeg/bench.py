#!/usr/bin/env python3
"""JPEG decode time of gait's still reader against cv2.imread, side by side (issue 33).

    target/python-venv/bin/python tools/jpeg/bench.py [--rounds 5] [--n 30]

Makes a 1920x1080 JPEG of a real frame (frame 100 of the sample video, scaled by ffmpeg, written by
cv2.imwrite at quality 95, 4:2:0) under target/jpeg-bench/, builds the release example
`still_bench` (the dev profile: dependencies such as libjpeg-turbo and image are built optimised,
as in the `gait` binary the tests use), then alternates rounds: the Rust example (N reads: gait's reader, then the `image`
crate), and N `cv2.imread` in this process. Prints each round and the ratio of the medians."""
import argparse
import json
import pathlib
import statistics
import subprocess
import time

import cv2

ROOT = pathlib.Path(__file__).resolve().parents[2]


def frame_1080p(out):
    if out.exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    png = out.with_suffix(".png")
    subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", str(ROOT / "../shared/data/sports2d-demo.mp4"),
                    "-vf", "select=eq(n\\,100),scale=1920:1080", "-frames:v", "1", str(png)], check=True)
    cv2.imwrite(str(out), cv2.imread(str(png)), [cv2.IMWRITE_JPEG_QUALITY, 95])
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--n", type=int, default=30)
    a = ap.parse_args()
    jpg = frame_1080p(ROOT / "target/jpeg-bench/frame_1080p.jpg")
    subprocess.run(["cargo", "build", "-q", "-p", "gait-pipeline", "--example", "still_bench"],
                   cwd=ROOT, check=True)
    exe = ROOT / "target/debug/examples/still_bench"
    gait, crate, cv = [], [], []
    for r in range(a.rounds):
        out = json.loads(subprocess.run([str(exe), str(jpg), str(a.n)], capture_output=True, text=True,
                                        check=True).stdout)
        times = []
        for _ in range(a.n):
            t = time.perf_counter()
            img = cv2.imread(str(jpg), cv2.IMREAD_COLOR)
            times.append((time.perf_counter() - t) * 1e3)
            assert img.shape == (1080, 1920, 3)
        gait.append(out["gait_ms"])
        crate.append(out["image_crate_ms"])
        cv.append(statistics.median(times))
        print(f"round {r + 1}: gait {gait[-1]:.2f} ms, cv2.imread {cv[-1]:.2f} ms, image crate {crate[-1]:.2f} ms")
    g, c, i = (statistics.median(x) for x in (gait, cv, crate))
    print(f"median of rounds: gait {g:.2f} ms, cv2.imread {c:.2f} ms (ratio {g / c:.3f}), image crate {i:.2f} ms "
          f"(ratio {i / c:.3f}); opencv {cv2.__version__}")


if __name__ == "__main__":
    main()
