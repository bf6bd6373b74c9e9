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
    from mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1);
  - edge_*.png, small_150.png (EDGE_CROPS): full-resolution crops of sample frames cut so the
    walker's body touches one image edge (the landmark crop then runs past that edge: issue 22),
    and a small image the walker fills; same palette treatment; their landmarks in
    mediapipe_edges.json (same format; a separate file so mediapipe.json stays as it was);
  - imagetotensor.json: sha256 of the 8-bit crops mediapipe's own ImageToTensorCalculator makes
    (kind "letterbox": the detector's zero-bordered input; "detection": the landmark crop of
    mediapipe's own detection, pose_rect_from_detection, whose rectangle also lets the tests run
    the landmark stage on exactly mediapipe's crop; "random": seeded rotated / off-image
    rectangles, replicated or zero border) of every image above.
"""
import hashlib
import json
import os
import subprocess
import sys
import tempfile

import cv2
import mediapipe as mp
import numpy as np
from google.protobuf import text_format
from mediapipe.calculators.tensor import image_to_tensor_calculator_pb2  # noqa: F401 (registers the options)
from mediapipe.framework import calculator_pb2
from mediapipe.framework.formats import rect_pb2
from mediapipe.python import packet_creator, packet_getter
from mediapipe.python.solution_base import SolutionBase
from PIL import Image
from skimage import data

FRAMES = [100, 150, 200, 229]
# name: (frame, (left, top, right, bottom) in the 1768x994 frame, output size or None).
EDGE_CROPS = {
    "edge_bottom_150.png": (150, (200, 420, 900, 940), None),  # cuts the right toe and the heels
    "edge_top_120.png": (120, (520, 530, 1180, 994), None),  # cuts the top of the head
    "edge_left_150.png": (150, (430, 440, 1000, 994), None),  # cuts the left (back) toe
    "edge_right_120.png": (120, (500, 440, 930, 994), None),  # cuts the right heel
    "edge_legs_120.png": (120, (700, 640, 1400, 970), None),  # issue 22: hips and legs only
    "small_150.png": (150, (140, 488, 900, 958), (550, 340)),  # the walker fills a small image
}
OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-pose", "tests", "fixtures", "blazepose")


def small_png(img: Image.Image, path: str) -> None:
    q = img.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    q.save(path, optimize=True)


def extract_frame(video: str, f: int, tmp: str) -> Image.Image:
    raw = os.path.join(tmp, f"{f}.png")
    subprocess.run(
        ["ffmpeg", "-v", "error", "-y", "-i", video, "-vf", f"select=eq(n\\,{f})", "-frames:v", "1", raw],
        check=True,
    )
    return Image.open(raw)


def load_rgb(name: str) -> np.ndarray:
    bgr = cv2.imread(os.path.join(OUT, name), cv2.IMREAD_COLOR)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def landmarks_json(names: list, path: str) -> None:
    result = {
        "generator": f"mediapipe {mp.__version__}, opencv {cv2.__version__}, "
        "mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1)",
        "images": {},
    }
    for name in names:
        rgb = load_rgb(name)
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
    with open(path, "w") as fh:
        json.dump(result, fh, indent=1)


TENSOR_GRAPH = """
input_stream: "image"
input_stream: "roi"
output_stream: "floats"
node { calculator: "ImageToTensorCalculator" input_stream: "IMAGE:image" input_stream: "NORM_RECT:roi"
  output_stream: "TENSORS:tensors"
  options { [mediapipe.ImageToTensorCalculatorOptions.ext] { output_tensor_width: %d output_tensor_height: %d
    keep_aspect_ratio: true output_tensor_float_range { min: 0.0 max: 1.0 } border_mode: %s } } }
node { calculator: "TensorsToFloatsCalculator" input_stream: "TENSORS:tensors" output_stream: "FLOATS:floats" }
"""


def mediapipe_crop(rgb: np.ndarray, roi: list, size: int, border: str) -> bytes:
    """The 8-bit crop of mediapipe's ImageToTensorCalculator (CPU), read back from its [0, 1] tensor."""
    mode = {"replicate": "BORDER_REPLICATE", "zero": "BORDER_ZERO"}[border]
    config = text_format.Parse(TENSOR_GRAPH % (size, size, mode), calculator_pb2.CalculatorGraphConfig())
    graph = mp.CalculatorGraph(graph_config=config)
    out = []
    graph.observe_output_stream("floats", lambda _, packet: out.append(packet_getter.get_float_list(packet)))
    graph.start_run()
    rect = rect_pb2.NormalizedRect(x_center=roi[0], y_center=roi[1], width=roi[2], height=roi[3], rotation=roi[4])
    graph.add_packet_to_input_stream("image", packet_creator.create_image_frame(data=rgb, image_format=mp.ImageFormat.SRGB).at(0))
    graph.add_packet_to_input_stream("roi", packet_creator.create_proto(rect).at(0))
    graph.close()
    return np.rint(np.array(out[0], np.float64) * 255).astype(np.uint8).tobytes()


def detection_roi(rgb: np.ndarray):
    """mediapipe's landmark-crop rectangle from its own detection (pose_rect_from_detection), or None."""
    pose = SolutionBase(
        binary_graph_path="mediapipe/modules/pose_landmark/pose_landmark_cpu.binarypb",
        side_inputs={"model_complexity": 1, "smooth_landmarks": False, "enable_segmentation": False,
                     "smooth_segmentation": False, "use_prev_landmarks": False},
        outputs=["pose_rect_from_detection"],
    )
    r = pose.process(input_data={"image": rgb}).pose_rect_from_detection
    pose.close()
    return None if r is None else [r.x_center, r.y_center, r.width, r.height, r.rotation]


def imagetotensor_json(names: list, path: str) -> None:
    rng = np.random.default_rng(22)
    crops = []
    for name in names:
        rgb = load_rgb(name)
        h, w = rgb.shape[:2]
        cases = [("letterbox", [0.5, 0.5, 1.0, 1.0, 0.0], 224, "zero")]  # the detector's input
        roi = detection_roi(rgb)
        if roi is not None:  # the landmark model's input
            cases.append(("detection", roi, 256, "replicate"))
        for i in range(4):
            side = rng.uniform(0.3, 1.8)
            rand = [rng.uniform(-0.2, 1.2), rng.uniform(-0.2, 1.2), side * h / w * rng.uniform(0.8, 1.2), side,
                    rng.uniform(-3.2, 3.2) if i % 2 else 0.0]
            cases.append(("random", rand, 256, "zero" if i == 3 else "replicate"))
        for kind, roi, size, border in cases:
            roi = [float(np.float32(v)) for v in roi]  # NormalizedRect holds f32
            digest = hashlib.sha256(mediapipe_crop(rgb, roi, size, border)).hexdigest()
            crops.append({"image": name, "kind": kind, "roi": roi, "size": size, "border": border, "sha256": digest})
    result = {"generator": f"mediapipe {mp.__version__} ImageToTensorCalculator (CPU, OpenCV)", "crops": crops}
    with open(path, "w") as fh:
        json.dump(result, fh, indent=1)


def main() -> None:
    video = sys.argv[1]
    os.makedirs(OUT, exist_ok=True)
    names = []
    edges = []
    with tempfile.TemporaryDirectory() as tmp:
        for f in FRAMES:
            name = f"frame_{f:03d}.png"
            small_png(extract_frame(video, f, tmp).resize((640, 360), Image.LANCZOS), os.path.join(OUT, name))
            names.append(name)
        for name, (f, box, size) in EDGE_CROPS.items():
            img = extract_frame(video, f, tmp).crop(box)
            small_png(img if size is None else img.resize(size, Image.LANCZOS), os.path.join(OUT, name))
            edges.append(name)
    small_png(Image.fromarray(data.astronaut()), os.path.join(OUT, "astronaut.png"))
    names.append("astronaut.png")

    landmarks_json(names, os.path.join(OUT, "mediapipe.json"))
    landmarks_json(edges, os.path.join(OUT, "mediapipe_edges.json"))
    imagetotensor_json(names + edges, os.path.join(OUT, "imagetotensor.json"))


if __name__ == "__main__":
    main()
