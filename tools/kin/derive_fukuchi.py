#!/usr/bin/env python3
"""Derive a small sagittal DeepLabCut-layout CSV from the Fukuchi 2018 example trial in gaitkit.

Source: `gaitkit==1.5.0` sdist on PyPI, file `src/gaitkit/data/example_healthy.json`
(Fukuchi, Fukuchi & Duarte 2018, "A public dataset of overground and treadmill walking kinematics
and kinetics in healthy individuals", PeerJ 6:e4640, doi:10.7717/peerj.4640; CC-BY 4.0).

Needs only the Python standard library. Regenerate:

    pip download --no-deps --no-binary=:all: gaitkit==1.5.0   # or copy the sdist from pip's cache
    tar xzf gaitkit-1.5.0.tar.gz
    python3 tools/kin/derive_fukuchi.py gaitkit-1.5.0/src/gaitkit/data/example_healthy.json tests/data/fukuchi2018

(`pip download` of this sdist builds its metadata and may need a long build-dependency install; the
tarball itself is what matters: sha256 de1f0c258152c5eac2e3d0382fb57e321c69091ee7923ce0849ff24d9640d861.)

Projection: the lab frame has x = walking direction, y = vertical (up), z = mediolateral (left is -z).
A camera on the subject's right side (+z) looking along -z sees image x = lab x and image y = -lab y.
We map 1 px = 2 mm and shift so that all coordinates are positive:
    u = (X - min X) / 2 + 50,  v = (max Y - Y) / 2 + 50.
Likelihood is 1 for every marker (mocap has no gaps in this trial).

Writes:
  keypoints.csv      DeepLabCut layout (scorer/bodyparts/coords), 10 lower-limb keypoints, 150 Hz
  events.csv         the file's annotated events: side,event,frame,time_s
  reference.csv      the file's reference angles per frame (see README.md for their definitions)
"""
import json
import sys
from pathlib import Path

NAMES = ["left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
         "left_heel", "right_heel", "left_toe", "right_toe"]
MM_PER_PX = 2.0


def main(src: str, out_dir: str, scorer: str = "fukuchi2018_mocap") -> None:
    """Projects one gaitkit example trial (this file's format) into `out_dir`."""
    d = json.loads(Path(src).read_text())
    fps = float(d["fps"])
    frames = d["angle_frames"]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    xs = [f["landmark_positions"][n][0] for f in frames for n in NAMES]
    ys = [f["landmark_positions"][n][1] for f in frames for n in NAMES]
    x0, y1 = min(xs), max(ys)
    # The walk must go along +x for the camera-on-the-right convention above.
    first = frames[0]["landmark_positions"]
    last = frames[-1]["landmark_positions"]
    assert last["left_hip"][0] > first["left_hip"][0], "expected a walk along +x"
    assert first["right_hip"][2] > first["left_hip"][2], "expected the right side at +z"

    rows = [
        ",".join(["scorer"] + [scorer] * (3 * len(NAMES))),
        ",".join(["bodyparts"] + [n for n in NAMES for _ in range(3)]),
        ",".join(["coords"] + ["x", "y", "likelihood"] * len(NAMES)),
    ]
    for f in frames:
        cells = [str(f["frame_index"])]
        for n in NAMES:
            X, Y, _Z = f["landmark_positions"][n]
            cells += [f"{(X - x0) / MM_PER_PX + 50:.3f}", f"{(y1 - Y) / MM_PER_PX + 50:.3f}", "1"]
        rows.append(",".join(cells))
    (out / "keypoints.csv").write_text("\n".join(rows) + "\n")

    gt = d["ground_truth"]
    ev = []
    for kind, key in (("heel_strike", "hs_frames"), ("toe_off", "to_frames")):
        for side in ("left", "right"):
            for fr in gt[key][side]:
                ev.append((fr, side, kind))
    ev.sort()
    lines = ["side,event,frame,time_s"] + [f"{s},{k},{fr},{fr / fps:.6f}" for fr, s, k in ev]
    (out / "events.csv").write_text("\n".join(lines) + "\n")

    cols = ["left_hip_angle", "right_hip_angle", "left_knee_angle", "right_knee_angle",
            "left_ankle_angle", "right_ankle_angle"]
    lines = ["frame," + ",".join(c.replace("_angle", "") for c in cols)]
    for f in frames:
        lines.append(str(f["frame_index"]) + "," + ",".join(f"{f[c]:.4f}" for c in cols))
    (out / "reference.csv").write_text("\n".join(lines) + "\n")
    print(f"{len(frames)} frames at {fps} Hz, {len(ev)} events -> {out}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
