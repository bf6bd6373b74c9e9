#!/usr/bin/env python3
"""Reference fixtures for the BlazePose estimator's tracking (video mode) in crates/gait-pose.

Needs: Python 3.11 with mediapipe==0.10.14 opencv-contrib-python==4.10.0.84 (Pillow comes with them), and
ffmpeg on PATH. Regenerate (from the repository root):
    python3.11 -m venv /tmp/bp && /tmp/bp/bin/pip install mediapipe==0.10.14 opencv-contrib-python==4.10.0.84
    /tmp/bp/bin/python tools/blazepose/make_tracking_fixtures.py /work/shared/data/sports2d-demo.mp4

Writes into crates/gait-pose/tests/fixtures/blazepose/:
  - track_NNN.png: COUNT consecutive frames of the sample video from FIRST on, decoded as gait decodes a
    video (ffmpeg, rawvideo rgb24, crates/gait-pipeline/src/video_decoder.rs), downscaled to 640x360 and
    stored as 256-colour palette PNGs (as make_fixtures.py does), so mediapipe and the Rust tests see
    exactly the same pixels;
  - mediapipe_tracking.json: mediapipe's result on those frames, in order, from ONE graph in video mode, as
    mp.solutions.pose.Pose(static_image_mode=False, smooth_landmarks=False, model_complexity=1) runs it
    (same graph, side inputs, thresholds and 33,333 us timestamp steps); per frame:
      "landmarks": the 33 landmarks [x, y, z, visibility] (normalised), or null;
      "rect_from_landmarks": the crop for the NEXT frame, [x_centre, y_centre, width, height, rotation]
        (pose_rect_from_landmarks: built from landmarks 33/34 after the One-Euro filter mediapipe always
        runs on them in video mode), or null;
      "rect_from_detection": the crop from a detection where mediapipe detected in this frame, else null;
      "aux_unfiltered", "aux_filtered": landmarks 33 and 34 [x, y] (normalised) as the landmark model gives
        them (graph stream unfiltered_auxiliary_landmarks) and after the One-Euro filter (auxiliary_landmarks),
        or null; the two streams are made graph outputs for this, nothing else changes.
    The script checks that mp.solutions.pose.Pose itself gives the same landmarks.
"""
import json
import os
import subprocess
import sys

import cv2
import mediapipe as mp
import numpy as np
from mediapipe.framework import calculator_pb2
from mediapipe.python.solution_base import SolutionBase
from PIL import Image

FIRST = 100
COUNT = 30
SIZE = (640, 360)
OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-pose", "tests", "fixtures", "blazepose")


def small_png(img: Image.Image, path: str) -> None:
    q = img.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    q.save(path, optimize=True)


def decode_frames(video: str, first: int, count: int) -> list:
    """Frames first .. first + count - 1 as gait decodes them (the same ffmpeg command)."""
    probe = subprocess.run(
        ["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=width,height",
         "-of", "csv=p=0", video],
        check=True, capture_output=True, text=True,
    )
    w, h = (int(v) for v in probe.stdout.strip().split(",")[:2])
    proc = subprocess.Popen(
        ["ffmpeg", "-v", "error", "-nostdin", "-i", video, "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
        stdout=subprocess.PIPE,
    )
    frames = []
    n = 0
    while len(frames) < count:
        buf = proc.stdout.read(w * h * 3)
        if len(buf) < w * h * 3:
            raise SystemExit(f"video ended after {n} frames")
        if n >= first:
            frames.append(Image.fromarray(np.frombuffer(buf, np.uint8).reshape(h, w, 3)))
        n += 1
    proc.kill()
    proc.wait()
    return frames


def load_rgb(name: str) -> np.ndarray:
    bgr = cv2.imread(os.path.join(OUT, name), cv2.IMREAD_COLOR)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def rect(r) -> list:
    return None if r is None else [float(r.x_center), float(r.y_center), float(r.width), float(r.height),
                                   float(r.rotation)]


def landmarks(res) -> list:
    if res is None:
        return None
    return [[float(l.x), float(l.y), float(l.z), float(l.visibility)] for l in res.landmark]


def aux(res) -> list:
    return None if res is None else [[float(l.x), float(l.y)] for l in res.landmark]


def video_mode(names: list) -> list:
    """mediapipe in video mode over the frames in order: mp.solutions.pose.Pose's graph and settings, with
    the crop rectangles and landmarks 33/34 before and after the filter as extra outputs."""
    config = calculator_pb2.CalculatorGraphConfig()
    with open(os.path.join(os.path.dirname(mp.__file__), "modules", "pose_landmark", "pose_landmark_cpu.binarypb"),
              "rb") as fh:
        config.ParseFromString(fh.read())
    config.output_stream.extend(["AUX_UNFILTERED:unfiltered_auxiliary_landmarks", "AUX:auxiliary_landmarks"])
    graph = SolutionBase(
        graph_config=config,
        side_inputs={"model_complexity": 1, "smooth_landmarks": False, "enable_segmentation": False,
                     "smooth_segmentation": False, "use_prev_landmarks": True},
        calculator_params={
            "posedetectioncpu__TensorsToDetectionsCalculator.min_score_thresh": 0.5,
            "poselandmarkbyroicpu__tensorstoposelandmarksandsegmentation__ThresholdingCalculator.threshold": 0.5,
        },
        outputs=["pose_landmarks", "pose_rect_from_landmarks", "pose_rect_from_detection",
                 "unfiltered_auxiliary_landmarks", "auxiliary_landmarks"],
    )
    out = []
    for name in names:
        res = graph.process(input_data={"image": load_rgb(name)})
        out.append({
            "image": name,
            "landmarks": landmarks(res.pose_landmarks),
            "rect_from_landmarks": rect(res.pose_rect_from_landmarks),
            "rect_from_detection": rect(res.pose_rect_from_detection),
            "aux_unfiltered": aux(res.unfiltered_auxiliary_landmarks),
            "aux_filtered": aux(res.auxiliary_landmarks),
        })
    graph.close()
    # The public API on the same frames must give the same landmarks (same graph, same timestamps).
    with mp.solutions.pose.Pose(static_image_mode=False, smooth_landmarks=False, model_complexity=1) as pose:
        for entry in out:
            got = landmarks(pose.process(load_rgb(entry["image"])).pose_landmarks)
            assert got == entry["landmarks"], f"{entry['image']}: Pose() differs from the graph run"
    return out


def main() -> None:
    video = sys.argv[1]
    os.makedirs(OUT, exist_ok=True)
    names = []
    for i, img in enumerate(decode_frames(video, FIRST, COUNT)):
        name = f"track_{FIRST + i:03d}.png"
        small_png(img.resize(SIZE, Image.LANCZOS), os.path.join(OUT, name))
        names.append(name)
    frames = video_mode(names)
    for f in frames:
        print(f["image"], "detected" if f["rect_from_detection"] else "tracked",
              "found" if f["landmarks"] else "nobody")
    result = {
        "generator": f"mediapipe {mp.__version__}, opencv {cv2.__version__}, "
        "mp.solutions.pose.Pose(static_image_mode=False, smooth_landmarks=False, model_complexity=1), "
        "frames in order, timestamps 33333 us apart",
        "frames": frames,
    }
    with open(os.path.join(OUT, "mediapipe_tracking.json"), "w") as fh:
        json.dump(result, fh, indent=1)


if __name__ == "__main__":
    main()
