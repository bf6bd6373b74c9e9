"""Selfie-segmentation masks from MediaPipe, for crates/gait-tflite/tests/selfie.rs.

Needs: python 3.11, mediapipe==0.10.14, numpy, pillow.
Regenerate: python tools/edge/make_selfie_fixtures.py
Reads the BlazePose fixture frames, resizes each to 256x256 (the model's input
size, so MediaPipe's own resize is the identity), runs
`mp.solutions.selfie_segmentation.SelfieSegmentation(model_selection=0)` and
writes the input PNG and the float mask (raw probability, little-endian f32,
256*256 values, row-major) next to the test.
"""

import pathlib

import mediapipe as mp
import numpy as np
from PIL import Image

ROOT = pathlib.Path(__file__).resolve().parents[2]
SRC = ROOT / "crates/gait-pose/tests/fixtures/blazepose"
OUT = ROOT / "crates/gait-tflite/tests/fixtures"
# The edge_* frames (tools/blazepose/make_fixtures.py) have the person touching one image border
# each: the mask must agree there too.
NAMES = ["frame_150", "astronaut", "edge_bottom_150", "edge_top_120", "edge_left_150", "edge_right_120"]

OUT.mkdir(parents=True, exist_ok=True)
with mp.solutions.selfie_segmentation.SelfieSegmentation(model_selection=0) as seg:
    for name in NAMES:
        img = Image.open(SRC / f"{name}.png").convert("RGB").resize((256, 256), Image.BILINEAR)
        img.save(OUT / f"selfie_{name}.png")
        mask = seg.process(np.asarray(img)).segmentation_mask
        assert mask.shape == (256, 256), mask.shape
        mask.astype("<f4").tofile(OUT / f"selfie_{name}.f32")
        print(name, float(mask.min()), float(mask.max()), float(mask.mean()))
