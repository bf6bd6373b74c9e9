#!/usr/bin/env python3
"""Canny / resize fixtures for crates/gait-edge, produced by OpenCV itself.

Needs: Python 3.11, `pip install opencv-python-headless==4.12.0.88 numpy==2.4.6 scikit-image==0.26.0`,
and the `ffmpeg` CLI. Regenerate from the repo root:

    python3 tools/edge/make_canny_fixtures.py

Inputs (real photographs, cropped to keep the fixtures small):
- frames of /work/shared/data/sports2d-demo.mp4 (Sports2D demo video, BSD-3-Clause, (c) David Pagnon),
  path overridable with GAIT_SAMPLE_VIDEO;
- scikit-image sample images: astronaut (NASA, public domain), chelsea (CC0, Stefan van der Walt),
  coffee (CC0, Rachel Michetti).

Outputs in crates/gait-edge/tests/fixtures/canny/:
- NAME.rgb.png, NAME.gray.png: the inputs (gray = cv2.cvtColor(RGB2GRAY));
- NAME.rgb.canny.png, NAME.gray.canny.png: cv2.Canny(img, 100, 200);
- NAME.rgb.canny_l2.png: cv2.Canny(img, 100, 200, L2gradient=True);
- NAME.rgb.canny_50_120.png: cv2.Canny(img, 50, 120);
- annotator.rgb.png (a crop larger than 512 on its short side), annotator.resized.png (its resize the way
  controlnet_aux's resize_image does it: short side 512, sides multiples of 64, INTER_AREA when shrinking)
  and annotator.canny.png (cv2.Canny of that resized image: the ControlNet canny annotator's output).
"""

import os
import subprocess
import tempfile
from pathlib import Path

import cv2
import numpy as np
import skimage.data

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "crates/gait-edge/tests/fixtures/canny"
VIDEO = Path(os.environ.get("GAIT_SAMPLE_VIDEO", "/work/shared/data/sports2d-demo.mp4"))


def video_frame(index: int) -> np.ndarray:
    """Frame `index` of the sample video as RGB uint8 (decoded by ffmpeg)."""
    with tempfile.TemporaryDirectory() as tmp:
        png = Path(tmp) / "f.png"
        subprocess.run(
            ["ffmpeg", "-v", "error", "-i", str(VIDEO), "-vf", f"select=eq(n\\,{index})",
             "-frames:v", "1", str(png)],
            check=True,
        )
        bgr = cv2.imread(str(png), cv2.IMREAD_COLOR)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def save_rgb(path: Path, rgb: np.ndarray) -> None:
    assert cv2.imwrite(str(path), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))


def save_gray(path: Path, gray: np.ndarray) -> None:
    assert cv2.imwrite(str(path), gray)


def controlnet_resize(img: np.ndarray, resolution: int = 512) -> np.ndarray:
    """controlnet_aux.util.resize_image, restated."""
    h, w = img.shape[:2]
    k = float(resolution) / min(h, w)
    nh = int(np.round(h * k / 64.0)) * 64
    nw = int(np.round(w * k / 64.0)) * 64
    interp = cv2.INTER_LANCZOS4 if k > 1 else cv2.INTER_AREA
    return cv2.resize(img, (nw, nh), interpolation=interp)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    frame_a = video_frame(40)   # person jumping on a box, cluttered background
    frame_b = video_frame(170)  # woman walking in sagittal view
    inputs = {
        "video40": frame_a[300:700, 700:1100],
        "video170": frame_b[350:750, 800:1200],
        "astronaut": skimage.data.astronaut()[0:320, 96:416],
        "chelsea": skimage.data.chelsea()[0:300, 60:380],
        "coffee": skimage.data.coffee()[40:360, 140:460],
    }
    for name, rgb in inputs.items():
        rgb = np.ascontiguousarray(rgb)
        gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
        save_rgb(OUT / f"{name}.rgb.png", rgb)
        save_gray(OUT / f"{name}.gray.png", gray)
        save_gray(OUT / f"{name}.rgb.canny.png", cv2.Canny(rgb, 100, 200))
        save_gray(OUT / f"{name}.gray.canny.png", cv2.Canny(gray, 100, 200))
        save_gray(OUT / f"{name}.rgb.canny_l2.png", cv2.Canny(rgb, 100, 200, L2gradient=True))
        save_gray(OUT / f"{name}.rgb.canny_50_120.png", cv2.Canny(rgb, 50, 120))

    # The whole annotator on a crop whose short side exceeds 512 (so INTER_AREA shrinks it).
    big = np.ascontiguousarray(frame_b[260:820, 700:1300])  # 600 x 560
    resized = controlnet_resize(big)
    save_rgb(OUT / "annotator.rgb.png", big)
    save_rgb(OUT / "annotator.resized.png", resized)
    save_gray(OUT / "annotator.canny.png", cv2.Canny(resized, 100, 200))
    print(f"opencv {cv2.__version__}, threads {cv2.getNumThreads()}; wrote {OUT}")


if __name__ == "__main__":
    main()
