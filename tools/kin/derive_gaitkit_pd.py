#!/usr/bin/env python3
"""Derive a sagittal DeepLabCut-layout CSV from the Parkinson's disease example trial in gaitkit.

Source: `gaitkit==1.5.0` sdist on PyPI (MIT-licensed package), file
`src/gaitkit/data/example_parkinson.json` (identical in gaitkit 0.1.0, 1.2.4, 1.3.1 and 1.4.9).
sha256 of `gaitkit-1.5.0.tar.gz`: de1f0c258152c5eac2e3d0382fb57e321c69091ee7923ce0849ff24d9640d861.
One overground walking trial of a person with Parkinson's disease, 150 Hz, annotated heel strikes
and toe-offs. gaitkit's own metadata is inconsistent about where it comes from (see
tests/data/gaitkit_pd/README.md): the JSON names "Goldberger et al., PhysioNet Gait in PD, ODC-By
1.0" and doi 10.6084/m9.figshare.7734767, while gaitkit's extractor for this data
(`extractors/figshare_pd_extractor.py`) reads the C3D files of Shida et al. 2023, "A public data
set of walking full-body kinematics and kinetics in individuals with Parkinson's disease",
Front. Neurosci. 17:992585 (figshare 14896881). Either way it is distributed under an open
attribution licence; we keep the attribution in the README.

Needs only the Python standard library. Regenerate:

    pip download --no-deps --no-binary=:all: gaitkit==1.5.0   # or copy the sdist from pip's cache
    tar xzf gaitkit-1.5.0.tar.gz
    python3 tools/kin/derive_gaitkit_pd.py gaitkit-1.5.0/src/gaitkit/data/example_parkinson.json tests/data/gaitkit_pd

Projection (as tools/kin/derive_fukuchi.py): lab x = walking direction, y = up, z = mediolateral
(right is +z). A camera on the subject's right sees image x = lab x, image y = -lab y; 1 px = 2 mm,
    u = (X - min X) / 2 + 50,  v = (max Y - Y) / 2 + 50,  likelihood 1 (no gaps in this trial).

Writes keypoints.csv (DeepLabCut layout, 10 lower-limb keypoints), events.csv
(side,event,frame,time_s: the file's annotated events) and reference.csv (the file's angles).
"""
import json
import sys
from pathlib import Path

NAMES = ["left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
         "left_heel", "right_heel", "left_toe", "right_toe"]
MM_PER_PX = 2.0


def main(src: str, out_dir: str) -> None:
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
        ",".join(["scorer"] + ["gaitkit_pd_mocap"] * (3 * len(NAMES))),
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
