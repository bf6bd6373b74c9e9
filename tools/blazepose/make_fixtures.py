#!/usr/bin/env python3
"""Reference fixtures for the BlazePose estimator in crates/gait-pose.

Needs: Python 3.11 with mediapipe==0.10.14 opencv-contrib-python==4.10.0.84 scikit-image==0.26.0
(Pillow comes with them), and ffmpeg on PATH.
Regenerate (from the repository root):
    python3.11 -m venv /tmp/bp && /tmp/bp/bin/pip install mediapipe==0.10.14 \
        opencv-contrib-python==4.10.0.84 scikit-image==0.26.0
    /tmp/bp/bin/python tools/blazepose/make_fixtures.py /work/shared/data/sports2d-demo.mp4

Writes into crates/gait-pose/tests/fixtures/blazepose/:
  - frame_NNN.png: frames of the sample video (walking part), downscaled to 640x360 and stored as
    256-colour palette PNGs so they stay small; lossless from here on, so mediapipe and the Rust
    tests see exactly the same pixels;
  - astronaut.png: scikit-image's astronaut photograph, same palette treatment;
  - mediapipe.json: for each image, mediapipe's 33 landmarks (normalised x, y, z and visibility)
    from mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1).
"""
import json
import os
import subprocess
import sys
import tempfile

import cv2
import mediapipe as mp
import numpy as np
from PIL import Image
from skimage import data

FRAMES = [100, 150, 200, 229]
OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-pose", "tests", "fixtures", "blazepose")


def small_png(img: Image.Image, path: str) -> None:
    q = img.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    q.save(path, optimize=True)


def main() -> None:
    video = sys.argv[1]
    os.makedirs(OUT, exist_ok=True)
    names = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in FRAMES:
            raw = os.path.join(tmp, f"{f}.png")
            subprocess.run(
                ["ffmpeg", "-v", "error", "-y", "-i", video, "-vf", f"select=eq(n\\,{f})", "-frames:v", "1", raw],
                check=True,
            )
            name = f"frame_{f:03d}.png"
            small_png(Image.open(raw).resize((640, 360), Image.LANCZOS), os.path.join(OUT, name))
            names.append(name)
    small_png(Image.fromarray(data.astronaut()), os.path.join(OUT, "astronaut.png"))
    names.append("astronaut.png")

    result = {
        "generator": f"mediapipe {mp.__version__}, opencv {cv2.__version__}, "
        "mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1)",
        "images": {},
    }
    for name in names:
        bgr = cv2.imread(os.path.join(OUT, name), cv2.IMREAD_COLOR)
        rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
        # A fresh solution per image: static mode, nothing carried over.
        with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1) as pose:
            res = pose.process(rgb)
        entry = {"width": rgb.shape[1], "height": rgb.shape[0], "landmarks": None}
        if res.pose_landmarks is not None:
            entry["landmarks"] = [
                [float(l.x), float(l.y), float(l.z), float(l.visibility)] for l in res.pose_landmarks.landmark
            ]
        result["images"][name] = entry
        print(name, "found" if entry["landmarks"] else "no person")
    with open(os.path.join(OUT, "mediapipe.json"), "w") as fh:
        json.dump(result, fh, indent=1)


if __name__ == "__main__":
    main()
