#!/usr/bin/env python3
"""Derive a sagittal DeepLabCut-layout CSV from the treadmill walking C3D shipped with gaitalytics.

Source: `gaitalytics==0.2.2` sdist on PyPI (MIT licence, (c) 2024 André Böni, DART lab), file
`tests/treadmill_events.c3d`: Vicon Nexus 2.14, 100 Hz, one healthy subject ("SI02") walking on a
split-belt instrumented treadmill (2 force plates at 1000 Hz), Human Body Model 2 marker set and
model outputs, 43 gait events (Foot Strike / Foot Off) in the C3D EVENT group.
sha256 of `gaitalytics-0.2.2.tar.gz`: 02fa69ade972c3d94c29796a090da7aa052d911d704184e732045c27f8a9409d
sha256 of `treadmill_events.c3d`:     206c0dfd718d7e3ea4ccb5afc2d094ecf35eef9a2dedc9a1c72490609eab2a97

Needs: pip install ezc3d==1.7.2 numpy. Regenerate:

    pip download --no-deps --no-binary=:all: gaitalytics==0.2.2   # needs setuptools for metadata
    tar xzf gaitalytics-0.2.2.tar.gz
    python3 tools/kin/derive_gaitalytics_treadmill.py gaitalytics-0.2.2/tests/treadmill_events.c3d \
        tests/data/gaitalytics_treadmill

Keypoints (lab: z up, walking towards -y, left side at +x):
    hip = {L,R}FEP (HBM2 femur proximal point = hip joint centre), knee = {L,R}FEO (femur origin =
    knee joint centre), ankle = {L,R}TIO (tibia origin = ankle joint centre), heel = {L,R}HEE
    marker, toe = {L,R}MT2 marker (2nd metatarsal head).
Projection: a camera on the subject's right (-x) looking along +x sees image x = forward = -lab y
and image y = -lab z; 1 px = 2 mm, shifted to positive pixels, likelihood 1 (no gaps). The belt
moves under the feet: this is what a fixed camera beside a treadmill sees (the pelvis stays put).

Events: Nexus stores an event's time t (s) with frame number t * rate + 1 counted from the start of
the capture; the file starts at capture frame TRIAL:ACTUAL_START_FIELD, so the 0-based row is
round(t * rate) + 1 - ACTUAL_START_FIELD. The script checks this against the force plates
(vertical force crossing 20 N on each belt) and prints the differences.

Writes keypoints.csv, events.csv (side,event,frame,time_s), reference.csv (Nexus model angles:
hip flexion, knee flexion, ankle dorsiflexion, degrees, per frame) and forceplate_events.csv
(the same events from the force plates, for the README's check).
"""
import sys
from pathlib import Path

import ezc3d
import numpy as np

PARTS = [("left_hip", "LFEP"), ("right_hip", "RFEP"), ("left_knee", "LFEO"), ("right_knee", "RFEO"),
         ("left_ankle", "LTIO"), ("right_ankle", "RTIO"), ("left_heel", "LHEE"),
         ("right_heel", "RHEE"), ("left_toe", "LMT2"), ("right_toe", "RMT2")]
MM_PER_PX = 2.0
FP_THRESHOLD_N = 20.0


def forceplate_events(c, first: int, rate: float):
    """(side, event, fractional 0-based point frame) from each belt's vertical force."""
    p = c["parameters"]
    labels = p["ANALOG"]["LABELS"]["value"]
    analog = c["data"]["analogs"][0]
    ratio = float(p["ANALOG"]["RATE"]["value"][0]) / rate
    corners = np.array(p["FORCE_PLATFORM"]["CORNERS"]["value"]).reshape(3, 4, -1)
    out = []
    for k in range(corners.shape[2]):
        # Left belt lies at +x (the left markers' side).
        side = "left" if corners[0, :, k].mean() > 0 else "right"
        fz = np.abs(analog[labels.index(f"Force.Fz{k + 1}")])
        on = fz > FP_THRESHOLD_N
        for i in np.flatnonzero(np.diff(on.astype(int))):
            kind = "heel_strike" if on[i + 1] else "toe_off"
            out.append((side, kind, (i + 1) / ratio))
    return out


def main(src: str, out_dir: str) -> None:
    c = ezc3d.c3d(src)
    p = c["parameters"]
    rate = float(p["POINT"]["RATE"]["value"][0])
    start = int(p["TRIAL"]["ACTUAL_START_FIELD"]["value"][0])
    labels = p["POINT"]["LABELS"]["value"]
    pts = c["data"]["points"][:3]
    n = pts.shape[2]
    xyz = {name: pts[:, labels.index(lab), :] for name, lab in PARTS}
    for name, v in xyz.items():
        assert np.isfinite(v).all() and (np.abs(v).sum(0) > 0).all(), f"gap in {name}"
    # Check the axes: left side at +x, pelvis in front of the feet... walking towards -y.
    assert (xyz["left_hip"][0] > xyz["right_hip"][0]).all()
    assert np.median(xyz["left_toe"][1] - xyz["left_heel"][1]) < 0, "toes should point to -y"
    fwd = {k: -v[1] for k, v in xyz.items()}
    up = {k: v[2] for k, v in xyz.items()}
    f0 = min(v.min() for v in fwd.values())
    z1 = max(v.max() for v in up.values())

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = [n for n, _ in PARTS]
    rows = [
        ",".join(["scorer"] + ["gaitalytics_treadmill_mocap"] * (3 * len(names))),
        ",".join(["bodyparts"] + [m for m in names for _ in range(3)]),
        ",".join(["coords"] + ["x", "y", "likelihood"] * len(names)),
    ]
    for i in range(n):
        cells = [str(i)]
        for m in names:
            cells += [f"{(fwd[m][i] - f0) / MM_PER_PX + 50:.3f}",
                      f"{(z1 - up[m][i]) / MM_PER_PX + 50:.3f}", "1"]
        rows.append(",".join(cells))
    (out / "keypoints.csv").write_text("\n".join(rows) + "\n")

    ev = p["EVENT"]
    times = np.array(ev["TIMES"]["value"])[1]
    events = []
    for ctx, lab, t in zip(ev["CONTEXTS"]["value"], ev["LABELS"]["value"], times):
        side = {"Left": "left", "Right": "right"}[ctx]
        kind = {"Foot Strike": "heel_strike", "Foot Off": "toe_off"}[lab]
        frame = int(round(t * rate)) + 1 - start
        if 0 <= frame < n:
            events.append((frame, side, kind))
    events.sort()
    lines = ["side,event,frame,time_s"] + [f"{s},{k},{f},{f / rate:.6f}" for f, s, k in events]
    (out / "events.csv").write_text("\n".join(lines) + "\n")

    fp = forceplate_events(c, start, rate)
    lines = ["side,event,frame"] + [f"{s},{k},{f:.1f}" for s, k, f in sorted(fp, key=lambda e: e[2])]
    (out / "forceplate_events.csv").write_text("\n".join(lines) + "\n")
    for kind in ("heel_strike", "toe_off"):
        d = []
        for f, s, k in events:
            if k != kind:
                continue
            near = [g for s2, k2, g in fp if s2 == s and k2 == k and abs(g - f) < 10]
            if near:
                d.append(f - min(near, key=lambda g: abs(g - f)))
        print(f"{kind}: annotation - force plate (frames): mean {np.mean(d):+.2f}, "
              f"range {min(d):+.1f}..{max(d):+.1f}, n {len(d)}")

    ref = {}
    for side, pre in (("left", "L"), ("right", "R")):
        for joint, lab in (("hip", "HipAngles"), ("knee", "KneeAngles"), ("ankle", "AnkleAngles")):
            ref[f"{side}_{joint}"] = pts[0, labels.index(pre + lab), :]
    cols = ["left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle"]
    lines = ["frame," + ",".join(cols)]
    for i in range(n):
        lines.append(f"{i}," + ",".join(f"{ref[c][i]:.4f}" for c in cols))
    (out / "reference.csv").write_text("\n".join(lines) + "\n")
    print(f"{n} frames at {rate} Hz, {len(events)} events -> {out}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
