#!/usr/bin/env python3
"""Fixtures for gait-eval's metric tests, with expected values from an
independent numpy implementation of the metrics.

Needs: Python 3.11, numpy==2.2.6 (`pip install numpy==2.2.6`).
Regenerate (from the repo root):
    python3 tools/eval/make_fixtures.py crates/gait-eval/tests/fixtures/metrics

Writes into the folder:
  truth.csv            ground truth, DeepLabCut CSV with x,y only (manual labels),
                       OpenPose-style names (RHip, LKnee, RBigToe, ...), frames 0..59
  pred_openpose/       prediction as OpenPose BODY_25 JSON, frames 0..69, with
                       injected failures (missing, low-confidence, swapped, misplaced)
  truth_angles.csv     joint angles (synthetic) of the truth, `angles.csv` layout
  pred_angles.csv      ... of the prediction (noisy, some cells empty)
  expected.json        metrics computed below with numpy

Metric definitions (the same as crates/gait-eval/src/failure.rs documents):
MAE = mean Euclidean distance over frames where truth found and prediction
found with confidence >= MIN_LIK; SD with ddof=1; legs pool hip, knee, ankle,
toe (+heel) of a side. Failure modes per frame, in order: not identified ->
swapped (cross-side sum beats same-side sum by > SWAP_FRAC * L per pair) ->
misidentified (error > MISID_FRAC * L), L = median truth thigh length.
"""
import json
import os
import sys

import numpy as np

MIN_LIK = 0.5
MISID_FRAC = 0.5
SWAP_FRAC = 0.1
N_TRUTH, N_PRED, FPS = 60, 70, 30.0

BODY_25 = ["Nose", "Neck", "RShoulder", "RElbow", "RWrist", "LShoulder", "LElbow", "LWrist", "MidHip",
           "RHip", "RKnee", "RAnkle", "LHip", "LKnee", "LAnkle", "REye", "LEye", "REar", "LEar",
           "LBigToe", "LSmallToe", "LHeel", "RBigToe", "RSmallToe", "RHeel"]
PARTS = ["Hip", "Knee", "Ankle", "BigToe"]
CANON = {"Hip": "hip", "Knee": "knee", "Ankle": "ankle", "BigToe": "toe"}
SIDES = {"L": "left", "R": "right"}


def skeleton(n, rng):
    """Truth keypoints [frame, name] -> (x, y) of a figure walking to the right."""
    f = np.arange(n)
    pts = {}
    for s, phase in (("L", 0.0), ("R", np.pi)):
        hip = np.stack([300 + 3.0 * f + (4 if s == "L" else -4), 200 + 2 * np.sin(2 * np.pi * f / 15)], 1)
        th = np.radians(25) * np.sin(2 * np.pi * f / 30 + phase)
        kn = np.radians(30) * (1 + np.sin(2 * np.pi * f / 30 + phase + 1.0)) / 2
        knee = hip + 100 * np.stack([np.sin(th), np.cos(th)], 1)
        ankle = knee + 95 * np.stack([np.sin(th - kn), np.cos(th - kn)], 1)
        toe = ankle + np.array([25.0, 6.0])
        for part, v in zip(PARTS, (hip, knee, ankle, toe)):
            pts[s + part] = v + rng.normal(0, 0.5, v.shape)
    return pts


def main(out):
    rng = np.random.default_rng(20261122)
    os.makedirs(os.path.join(out, "pred_openpose"), exist_ok=True)
    truth = skeleton(N_PRED, rng)
    names = [s + p for s in "RL" for p in PARTS]
    T = np.full((N_TRUTH, len(names), 2), np.nan)
    for k, nm in enumerate(names):
        T[:, k] = truth[nm][:N_TRUTH]
    T[5, names.index("LBigToe")] = np.nan          # a label missing in the truth
    T[50, names.index("LHip")] = np.nan
    T[50, names.index("RHip")] = np.nan
    T = np.round(T, 3)
    with open(os.path.join(out, "truth.csv"), "w") as fh:
        fh.write("scorer" + ",labeller" * 2 * len(names) + "\n")
        fh.write("bodyparts" + "".join(f",{n},{n}" for n in names) + "\n")
        fh.write("coords" + ",x,y" * len(names) + "\n")
        for i in range(N_TRUTH):
            cells = []
            for k in range(len(names)):
                cells += ["" if np.isnan(v) else repr(float(v)) for v in T[i, k]]
            fh.write(f"labeled-data/walk/img{i:04d}.png," + ",".join(cells) + "\n")

    # Prediction: all BODY_25 points; lower limbs from the truth plus noise.
    P = np.zeros((N_PRED, 25, 3))
    for nm in BODY_25:
        j = BODY_25.index(nm)
        if nm in truth:
            P[:, j, :2] = truth[nm] + rng.normal(0, 4.0, (N_PRED, 2))
        else:
            P[:, j, :2] = truth["LHip"] + np.array([rng.uniform(-50, 50), -rng.uniform(20, 300)])
        P[:, j, 2] = rng.uniform(0.6, 1.0, N_PRED)
    for nm in ("LHeel", "RHeel", "LSmallToe", "RSmallToe"):  # not labelled in the truth: not found
        P[:, BODY_25.index(nm)] = 0.0
    lower = [s + p for s in "LR" for p in PARTS]
    for f in (10, 11, 12):                        # right knee not found
        P[f, BODY_25.index("RKnee")] = 0.0
    P[40, BODY_25.index("LAnkle"), 2] = 0.3        # found, below MIN_LIK
    for f in (20, 21, 22, 65):                     # whole legs swapped
        for p in PARTS:
            a, b = BODY_25.index("L" + p), BODY_25.index("R" + p)
            P[f, [a, b]] = P[f, [b, a]]
    for f in (30, 31):                             # right ankle misplaced
        P[f, BODY_25.index("RAnkle"), :2] += np.array([70.0, -40.0])
    P[35, BODY_25.index("LBigToe"), :2] += np.array([-30.0, 20.0])  # below the threshold
    P = np.round(P, 3)
    for f in range(N_PRED):
        doc = {"version": 1.3, "people": [{"person_id": [-1], "pose_keypoints_2d": [float(v) for v in P[f].ravel()],
                                           "face_keypoints_2d": [], "hand_left_keypoints_2d": [],
                                           "hand_right_keypoints_2d": []}]}
        with open(os.path.join(out, "pred_openpose", f"walk_{f:012d}_keypoints.json"), "w") as fh:
            json.dump(doc, fh)

    # Angles: smooth curves; the prediction adds noise and leaves cells empty.
    cols = ["left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle"]
    t = np.arange(N_PRED) / FPS
    A = np.stack([20 * np.sin(2 * np.pi * t + c) + 10 * (c % 3) for c in range(6)], 1)
    B = A + rng.normal(0, 3.0, A.shape)
    B[:, 3] += 5.0                                  # biased prosthetic knee
    A[7, 0] = np.nan
    B[15, 2] = np.nan
    B[16, :] = np.nan
    A, B = np.round(A, 4), np.round(B, 4)
    for name, M, n in (("truth_angles.csv", A, N_TRUTH), ("pred_angles.csv", B, N_PRED)):
        with open(os.path.join(out, name), "w") as fh:
            fh.write("frame,time_s," + ",".join(cols) + "\n")
            for i in range(n):
                fh.write(f"{i},{t[i]!r}," + ",".join("" if np.isnan(v) else repr(float(v)) for v in M[i]) + "\n")

    # ---- expected metrics, computed independently of the Rust code ----
    pred_xy = {nm: P[:N_TRUTH, BODY_25.index(nm), :2] for nm in lower}
    pred_ok = {nm: (P[:N_TRUTH, BODY_25.index(nm), 2] > 0) & (P[:N_TRUTH, BODY_25.index(nm), 2] >= MIN_LIK) for nm in lower}
    truth_xy = {nm: T[:, names.index(nm)] for nm in lower}
    truth_ok = {nm: ~np.isnan(truth_xy[nm][:, 0]) for nm in lower}

    def stat(v):
        v = np.asarray(v, float)
        return {"n": int(v.size), "mean": float(v.mean()) if v.size else None,
                "sd": float(v.std(ddof=1)) if v.size > 1 else None}

    def canon(nm):
        return SIDES[nm[0]] + "_" + CANON[nm[1:]]

    err = {nm: np.linalg.norm(pred_xy[nm] - truth_xy[nm], axis=1) for nm in lower}
    use = {nm: truth_ok[nm] & pred_ok[nm] for nm in lower}
    keypoints = {canon(nm): stat(err[nm][use[nm]]) for nm in lower}
    legs = {SIDES[s]: stat(np.concatenate([err[s + p][use[s + p]] for p in PARTS])) for s in "LR"}

    thighs = []
    for i in range(N_TRUTH):
        per = [np.linalg.norm(truth_xy[s + "Hip"][i] - truth_xy[s + "Knee"][i]) for s in "LR"
               if truth_ok[s + "Hip"][i] and truth_ok[s + "Knee"][i]]
        if per:
            thighs.append(np.mean(per))
    L = float(np.median(thighs))
    fails = {"not_identified": [], "swapped": [], "misidentified": []}
    side_ni = {"left": 0, "right": 0}
    side_mi = {"left": 0, "right": 0}
    total = 0
    for i in range(N_TRUTH):
        exp = {s: [s + p for p in PARTS if truth_ok[s + p][i]] for s in "LR"}
        if not exp["L"] and not exp["R"]:
            continue
        total += 1
        miss = {s: any(not pred_ok[nm][i] for nm in exp[s]) for s in "LR"}
        for s in "LR":
            side_ni[SIDES[s]] += miss[s]
        if miss["L"] or miss["R"]:
            fails["not_identified"].append(i)
            continue
        pairs = [p for p in PARTS if truth_ok["L" + p][i] and truth_ok["R" + p][i]]
        d = lambda a, b: float(np.linalg.norm(a - b))
        same = sum(d(pred_xy["L" + p][i], truth_xy["L" + p][i]) + d(pred_xy["R" + p][i], truth_xy["R" + p][i]) for p in pairs)
        cross = sum(d(pred_xy["L" + p][i], truth_xy["R" + p][i]) + d(pred_xy["R" + p][i], truth_xy["L" + p][i]) for p in pairs)
        if pairs and same - cross > SWAP_FRAC * L * len(pairs):
            fails["swapped"].append(i)
            continue
        wrong = {s: any(err[nm][i] > MISID_FRAC * L for nm in exp[s]) for s in "LR"}
        for s in "LR":
            side_mi[SIDES[s]] += wrong[s]
        if wrong["L"] or wrong["R"]:
            fails["misidentified"].append(i)

    def pct(k):
        return {"frames": k, "percent": 100.0 * k / total}

    failures = {k: pct(len(v)) for k, v in fails.items()}
    failures["any"] = pct(sum(len(v) for v in fails.values()))
    failures.update({"frames": total, "reference_length_px": L,
                     "swapped_frames": fails["swapped"], "not_identified_frames": fails["not_identified"],
                     "misidentified_frames": fails["misidentified"],
                     "by_side": {s: {"not_identified": pct(side_ni[s]), "misidentified": pct(side_mi[s])} for s in ("left", "right")}})

    diff = np.abs(B[:N_TRUTH] - A[:N_TRUTH])
    joints = {c: stat(diff[:, j][~np.isnan(diff[:, j])]) for j, c in enumerate(cols)}
    kin_legs = {s: stat(np.concatenate([diff[:, j][~np.isnan(diff[:, j])] for j, c in enumerate(cols) if c.startswith(s)]))
                for s in ("left", "right")}
    expected = {"options": {"prosthetic_side": "right", "min_likelihood": MIN_LIK, "misid_fraction": MISID_FRAC,
                            "swap_fraction": SWAP_FRAC},
                "frames_compared": N_TRUTH, "keypoints": keypoints, "legs": legs, "failures": failures,
                "joints": joints, "kinematics_legs": kin_legs}
    with open(os.path.join(out, "expected.json"), "w") as fh:
        json.dump(expected, fh, indent=1)
    print(json.dumps({"legs": legs, "kin_legs": kin_legs, "failures": {k: failures[k] for k in ("not_identified", "swapped", "misidentified")}}, indent=1))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "crates/gait-eval/tests/fixtures/metrics")
