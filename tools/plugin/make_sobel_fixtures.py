#!/usr/bin/env python3
"""Sobel fixtures for crates/gait-plugin (the example plugin plugins/sobel-edge), produced by OpenCV.

Needs: Python 3.11, `pip install opencv-python-headless==4.12.0.88 numpy==2.2.6`, and the `ffmpeg` CLI.
Regenerate from the repo root:

    python3 tools/plugin/make_sobel_fixtures.py

Input: frame 120 of data/sample/sports2d-demo.mp4 (Sports2D demo video, BSD-3-Clause, (c) David Pagnon; see
data/sample/LICENSE.md), scaled by ffmpeg to 320x180 to keep the fixture small.

Outputs in crates/gait-plugin/tests/fixtures/sobel/:
- frame.png: the RGB input;
- edges_tT.png: 255 where the Sobel gradient magnitude exceeds T (61.5, 200.05: picked so that no magnitude lies near them), else 0, computed by cv2.Sobel (3x3,
  BORDER_REFLECT_101, float32) on the float32 gray image 0.299 R + 0.587 G + 0.114 B (unrounded, BT.601).
The script checks that no magnitude lies within 0.005 of a threshold, so float rounding differences between
OpenCV and the plugin cannot flip a pixel and the test can demand exact equality.
"""

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
VIDEO = ROOT / "data/sample/sports2d-demo.mp4"
OUT = ROOT / "crates/gait-plugin/tests/fixtures/sobel"
FRAME = 120
THRESHOLDS = [61.5, 200.05]
MARGIN = 0.005


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    frame_png = OUT / "frame.png"
    subprocess.run(
        ["ffmpeg", "-v", "error", "-y", "-i", str(VIDEO), "-vf", f"select=eq(n\\,{FRAME}),scale=320:180",
         "-frames:v", "1", "-pix_fmt", "rgb24", str(frame_png)],
        check=True,
    )
    bgr = cv2.imread(str(frame_png), cv2.IMREAD_COLOR)
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    gray = r * np.float32(0.299) + g * np.float32(0.587) + b * np.float32(0.114)
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REFLECT_101)
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3, borderType=cv2.BORDER_REFLECT_101)
    mag = np.sqrt(gx * gx + gy * gy)
    for t in THRESHOLDS:
        closest = float(np.min(np.abs(mag - t)))
        if closest < MARGIN:
            sys.exit(f"threshold {t}: a magnitude lies {closest} from it; pick another threshold")
        edges = np.where(mag > t, 255, 0).astype(np.uint8)
        cv2.imwrite(str(OUT / f"edges_t{t}.png"), edges)
        print(f"threshold {t}: {int((edges > 0).sum())} edge pixels of {edges.size}, closest magnitude {closest:.4f}")


if __name__ == "__main__":
    main()
