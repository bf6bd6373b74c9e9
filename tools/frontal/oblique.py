#!/usr/bin/env python3
"""How far off the walking line may the camera stand? Projects gaitkit's two motion-capture trials
(the sources of tests/data/frontal, see derive_frontal.py) through a camera turned by ANGLE from the
walking direction (0: the walker comes straight toward it, 90: a side view of the left side, 180:
the walker walks straight away), runs `gait kin` on each projection with the view left to `auto`,
and compares with the 3-D truth:

- the view decided, and the heel strikes against the side view's own (the 90 deg run's), within 5
  frames at 150 Hz (one frame of a 30 fps video);
- in a front or back view, trunk lean, pelvic obliquity and hip adduction against the same angles
  taken from the 3-D markers in the lab's frontal plane (derive_frontal.frontal_angles), MAE over the
  frames of the accepted cycles;
- in a side view, knee flexion against the 3-D angle between thigh and shank, MAE over the same;
- whether `gait kin` warned that the walk runs obliquely to the camera, with its estimated angle
  (crates/gait-kin/src/walk_angle.rs; 0 straight toward or away, 90 across);
- then, with the camera looking along the walk from 0.5-1.5 m beside its line, the mean
  circumduction and heel offset per side (crates/gait-kin/src/frontal/feet.rs), against the
  camera on the line.

Clean projections (no pose-model noise). Needs only the Python standard library and a built `gait`:

    tar xzf target/gaitkit-sdist/gaitkit-1.5.0.tar.gz -C target/gaitkit-sdist
    python3 tools/frontal/oblique.py target/gaitkit-sdist/gaitkit-1.5.0/src/gaitkit/data \
        --gait target/debug/gait --work target/oblique [--md FILE] [--fixtures tests/data/oblique]

Camera: 1 m high, horizontal, f = 1400 px on 1920 x 1080, aimed at the middle of the walk and
placed so that the pelvis comes no nearer than 3.5 m.
"""
import argparse
import csv
import json
import math
import re
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import derive_frontal as df  # noqa: E402

ANGLES = (0, 10, 20, 30, 45, 60, 70, 80, 90, 100, 110, 120, 135, 150, 160, 170, 180)
# The projections kept as fixtures (tests/data/oblique, crates/gait-kin/tests/oblique.rs).
FIXTURES = {("gaitkit_pd", 30), ("gaitkit_pd", 60), ("fukuchi2018", 160)}
FIXTURES_BESIDE = {("gaitkit_pd", 0, 1000)}
NEAR_MM = 3500.0
HS_FRAMES = 5


# The camera moved this far (mm) to its right from the walking line, looking along it.
BESIDE_MM = (0, 500, 1000, 1500)
BESIDE_ANGLES = (0, 180)


class TurnedCamera:
    """A horizontal pinhole camera whose optical axis makes `angle` degrees with the walking
    direction's reverse (0: looking back along -x at the approaching walker), moved `beside`
    mm to its own right."""

    def __init__(self, angle, pelvis, floor_y, beside=0.0):
        a = math.radians(angle)
        # Looking along f; at 90 deg along +z, from the walker's left (right is +z).
        self.f = (-math.cos(a), 0.0, math.sin(a))
        self.up = (0.0, 1.0, 0.0)
        # Image right = f x up.
        self.r = (-self.f[2], 0.0, self.f[0])
        mid = [sum(p[i] for p in pelvis) / len(pelvis) for i in range(3)]
        reach = max(sum((p[i] - mid[i]) * -self.f[i] for i in range(3)) for p in pelvis)
        d = NEAR_MM + reach
        self.pos = (mid[0] - d * self.f[0] + beside * self.r[0], floor_y + df.CAMERA_HEIGHT_MM,
                    mid[2] - d * self.f[2] + beside * self.r[2])

    def project(self, p):
        q = [p[i] - self.pos[i] for i in range(3)]
        depth = sum(q[i] * self.f[i] for i in range(3))
        assert depth > 0, "point behind the camera"
        right = sum(q[i] * self.r[i] for i in range(3))
        up = sum(q[i] * self.up[i] for i in range(3))
        return (df.WIDTH / 2 + df.FOCAL_PX * right / depth, df.HEIGHT / 2 - df.FOCAL_PX * up / depth)


def knee_flexion_3d(lm, side):
    """Angle (deg) between the thigh (hip to knee) and the shank (knee to ankle) in 3-D."""
    a = df.sub(lm[f"{side}_knee"], lm[f"{side}_hip"])
    b = df.sub(lm[f"{side}_ankle"], lm[f"{side}_knee"])
    c = sum(x * y for x, y in zip(a, b)) / (df.norm(a) * df.norm(b))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def number(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return math.nan


def run_gait(gait, keypoints, out, height_m):
    """`gait kin` on the projection (the frame size given, so that it estimates the walk's
    angle)."""
    subprocess.run([gait, "kin", "--fps", "150", "--keypoints", str(keypoints), "--out", str(out),
                        "--set", f"kinematics.subject_height_m={height_m}", "--set", "report.pdf=false",
                        "--set", f"kinematics.frame_size=[{df.WIDTH}, {df.HEIGHT}]"],
                   check=True, capture_output=True)


def oblique_warning(out):
    """The angle of kin.json's warning about an oblique walk, or None without one."""
    for w in json.loads((out / "kin.json").read_text()).get("warnings", []):
        m = re.search(r"the walk runs about (\d+) deg off the camera's axis", w)
        if m:
            return int(m.group(1))
    return None


def accepted_frames(out):
    """{side: [frames of accepted cycles]}"""
    frames = {"left": [], "right": []}
    for q in read_csv(out / "cycle_quality.csv"):
        if q["accepted"] == "true":
            frames[q["side"]] += range(int(q["first_frame"]), int(q["last_frame"]) + 1)
    return frames


def mae(pairs):
    d = [abs(a - b) for a, b in pairs if math.isfinite(a) and math.isfinite(b)]
    return sum(d) / len(d) if d else math.nan


def analyse(trial_frames, out, with_trunk):
    view_file = out / "frontal_view.csv"
    view = read_csv(view_file)[0]["view"] if view_file.exists() else "sagittal"
    events = read_csv(out / "events.csv")
    hs = {s: [int(e["frame"]) for e in events if e["side"] == s and e["event"] == "heel_strike"]
          for s in ("left", "right")}
    acc = accepted_frames(out)
    res = {"view": view, "hs": hs, "cycles": {s: 0 for s in acc}}
    for q in read_csv(out / "cycle_quality.csv"):
        res["cycles"][q["side"]] += q["accepted"] == "true"
    if view == "sagittal":
        rows = {int(r["frame"]): r for r in read_csv(out / "angles.csv")}
        pairs = [(number(rows[i][f"{s}_knee"]), knee_flexion_3d(trial_frames[i]["landmark_positions"], s))
                 for s in acc for i in acc[s] if i in rows]
        res["mae"] = {"knee": mae(pairs)}
    else:
        rows = {int(r["frame"]): r for r in read_csv(out / "frontal_angles.csv")}
        res["mae"] = {}
        for m in (["trunk_lean"] if with_trunk else []) + ["pelvic_obliquity", "hip_adduction"]:
            pairs = []
            for s in acc:
                for i in acc[s]:
                    if i in rows:
                        ref = df.frontal_angles(trial_frames[i]["landmark_positions"], with_trunk)
                        pairs.append((number(rows[i][f"{s}_{m}"]), ref[f"{m}_{s}"]))
            res["mae"][m] = mae(pairs)
    return res


def feet(out):
    """Mean circumduction and heel offset per side (cm) from frontal_feet.csv."""
    rows = read_csv(out / "frontal_feet.csv")
    mean = {}
    for m in ("circumduction", "heel_offset"):
        for s in ("left", "right"):
            v = [float(r["value"]) for r in rows if r["measure"] == m and r["side"] == s]
            mean[(m, s)] = sum(v) / len(v) if v else math.nan
    return mean


def project(trial_frames, names, cam, out, scorer):
    image = [{n: cam.project(f["landmark_positions"][n]) for n in names} for f in trial_frames]
    out.mkdir(parents=True, exist_ok=True)
    df.write_keypoints(out / "keypoints.csv", scorer, names, trial_frames, image)
    return image


def heel_strike_match(hs, reference):
    """(matched within HS_FRAMES, missed, extra) against the reference heel strikes."""
    matched = missed = 0
    used = set()
    for s in reference:
        for r in reference[s]:
            near = [f for f in hs[s] if abs(f - r) <= HS_FRAMES and (s, f) not in used]
            if near:
                used.add((s, near[0]))
                matched += 1
            else:
                missed += 1
    extra = sum(len(hs[s]) for s in hs) - len(used)
    return matched, missed, extra


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data_dir", help="gaitkit-1.5.0/src/gaitkit/data")
    ap.add_argument("--gait", default="target/debug/gait")
    ap.add_argument("--work", default="target/oblique")
    ap.add_argument("--md", help="write the table here as well")
    ap.add_argument("--fixtures", help="also write the projections of FIXTURES (trial and angle) "
                    "into this folder, e.g. tests/data/oblique")
    args = ap.parse_args()
    lines = ["| trial | camera angle (deg) | view decided | oblique walk warned (estimated deg) | heel strikes "
             "within 5 frames of the side view's (missed / extra) | cycles L / R | MAE against 3-D (deg) |",
             "| --- | ---: | --- | --- | --- | --- | --- |"]
    for trial, (fname, scorer) in df.TRIALS.items():
        d = json.loads((Path(args.data_dir) / fname).read_text())
        frames = d["angle_frames"]
        with_trunk = df.has_marker(frames, "left_shoulder") and df.has_marker(frames, "right_shoulder")
        names = [n for n in df.NAMES if with_trunk or "shoulder" not in n]
        pelvis = [df.mid(f["landmark_positions"]["left_hip"], f["landmark_positions"]["right_hip"]) for f in frames]
        floor_y = min(f["landmark_positions"][f"{s}_heel"][1] for f in frames for s in ("left", "right"))
        height_m = df.leg_length_mm(frames) / 1000 / 0.491
        results = {}
        for angle in ANGLES:
            cam = TurnedCamera(angle, pelvis, floor_y)
            out = Path(args.work) / f"{trial}_{angle:03d}"
            project(frames, names, cam, out, scorer)
            if args.fixtures and (trial, angle) in FIXTURES:
                fixture = Path(args.fixtures) / f"{trial}_{angle:03d}"
                project(frames, names, cam, fixture, scorer)
                truth = {"camera_angle_deg": angle, "walk_angle_deg": min(angle, 180 - angle), "fps": 150,
                         "frame_size": [df.WIDTH, df.HEIGHT], "focal_px": df.FOCAL_PX}
                (fixture / "truth.json").write_text(json.dumps(truth) + "\n")
            run_gait(args.gait, out / "keypoints.csv", out / "kin", height_m)
            results[angle] = analyse(frames, out / "kin", with_trunk)
            results[angle]["warned"] = oblique_warning(out / "kin")
        reference = results[90]["hs"]
        for angle in ANGLES:
            r = results[angle]
            m, miss, extra = heel_strike_match(r["hs"], reference)
            maes = ", ".join(f"{k} {v:.1f}" for k, v in r["mae"].items())
            warned = "-" if r["warned"] is None else f"yes ({r['warned']})"
            lines.append(f"| {trial} | {angle} | {r['view']} | {warned} | {m} of {m + miss} ({miss} / {extra}) | "
                         f"{r['cycles']['left']} / {r['cycles']['right']} | {maes} |")
            print(lines[-1], flush=True)
        lines += beside_rows(args, trial, frames, names, pelvis, floor_y, height_m, scorer)
    if args.md:
        Path(args.md).write_text("\n".join(lines) + "\n")


def beside_rows(args, trial, frames, names, pelvis, floor_y, height_m, scorer):
    """The camera looking along the walk from beside its line: circumduction and heel offsets
    against the camera on the line."""
    rows = ["", f"| {trial}: camera beside the line (m) | view | circumduction L / R (cm) | "
            "heel offset L / R (cm) | warned |", "| --- | --- | --- | --- | --- |"]
    for angle in BESIDE_ANGLES:
        for beside in BESIDE_MM:
            cam = TurnedCamera(angle, pelvis, floor_y, beside)
            out = Path(args.work) / f"{trial}_{angle:03d}_beside{beside}"
            project(frames, names, cam, out, scorer)
            if args.fixtures and (trial, angle, beside) in FIXTURES_BESIDE:
                fixture = Path(args.fixtures) / out.name
                project(frames, names, cam, fixture, scorer)
                truth = {"camera_angle_deg": angle, "beside_mm": beside, "fps": 150,
                         "frame_size": [df.WIDTH, df.HEIGHT], "focal_px": df.FOCAL_PX}
                (fixture / "truth.json").write_text(json.dumps(truth) + "\n")
            run_gait(args.gait, out / "keypoints.csv", out / "kin", height_m)
            r = analyse(frames, out / "kin", False)
            m = feet(out / "kin")
            warned = oblique_warning(out / "kin")
            rows.append(f"| {'toward' if angle == 0 else 'away'}, {beside / 1000:.1f} | {r['view']} | "
                        f"{m[('circumduction', 'left')]:.1f} / {m[('circumduction', 'right')]:.1f} | "
                        f"{m[('heel_offset', 'left')]:.1f} / {m[('heel_offset', 'right')]:.1f} | "
                        f"{'-' if warned is None else warned} |")
            print(rows[-1], flush=True)
    return rows


if __name__ == "__main__":
    main()
