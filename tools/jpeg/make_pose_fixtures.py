#!/usr/bin/env python3
"""mediapipe BlazePose references for the full-body JPEG photographs in tests/data/jpeg/ (issue 33).

Each photograph is read the way the Rust side must read it, `cv2.imread(path, cv2.IMREAD_COLOR)`
(EXIF orientation applied) then BGR->RGB, and handed to mediapipe's Pose in static mode, a fresh
solution per image, exactly as tools/blazepose/make_fixtures.py does for its PNG frames.

Needs: the project's Python venv (tools/python/requirements.txt: mediapipe==0.10.14,
opencv-contrib-python==4.10.0.84), which tools/python/setup.sh builds into target/python-venv.
Regenerate (from the repository root):
    target/python-venv/bin/python tools/jpeg/make_pose_fixtures.py

Writes tests/data/jpeg/expected/mediapipe.json in the format of
crates/gait-pose/tests/fixtures/blazepose/mediapipe.json:
    {"generator": "...", "images": {name: {"width": W, "height": H,
     "landmarks": [[x, y, z, visibility] x 33] or null}}}
with x, y normalised to the decoded (oriented) image: pixel x = x * width, pixel y = y * height.
Fails (exit 1) when mediapipe finds no person in one of the photographs.
"""
import json
import os
import sys

import cv2
import mediapipe as mp

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
DATA = os.path.join(ROOT, "tests", "data", "jpeg")
OUT = os.path.join(DATA, "expected", "mediapipe.json")
# Real photographs of a full-body person (legs or feet visible); sources in tests/data/jpeg/README.md.
PHOTOS = ["audrybt1.jpg", "messi5.jpg", "object_detection_input.jpg"]


def main() -> int:
    result = {
        "generator": f"mediapipe {mp.__version__}, opencv {cv2.__version__}, cv2.imread(IMREAD_COLOR) -> RGB, "
        "mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1, smooth_landmarks=False, "
        "enable_segmentation=False)",
        "images": {},
    }
    missing = 0
    for name in PHOTOS:
        bgr = cv2.imread(os.path.join(DATA, name), cv2.IMREAD_COLOR)
        rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
        # A fresh solution per image: static mode, nothing carried over.
        with mp.solutions.pose.Pose(
            static_image_mode=True, model_complexity=1, smooth_landmarks=False, enable_segmentation=False
        ) as pose:
            res = pose.process(rgb)
        entry = {"width": rgb.shape[1], "height": rgb.shape[0], "landmarks": None}
        if res.pose_landmarks is not None:
            entry["landmarks"] = [
                [float(l.x), float(l.y), float(l.z), float(l.visibility)] for l in res.pose_landmarks.landmark
            ]
        else:
            missing += 1
        result["images"][name] = entry
        print(name, "found" if entry["landmarks"] else "no person")
    with open(OUT, "w") as fh:
        json.dump(result, fh, indent=1)
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
