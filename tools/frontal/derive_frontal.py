#!/usr/bin/env python3
"""Derive frontal-view (anterior and posterior camera) fixtures from gaitkit's motion-capture trials.

Sources: the `gaitkit==1.5.0` sdist on PyPI (sha256 of `gaitkit-1.5.0.tar.gz`:
de1f0c258152c5eac2e3d0382fb57e321c69091ee7923ce0849ff24d9640d861), files
`src/gaitkit/data/example_healthy.json` (Fukuchi et al. 2018, CC-BY 4.0) and
`src/gaitkit/data/example_parkinson.json` (Parkinson's disease trial; see tests/data/gaitkit_pd/README.md
for its attribution). The same trials give the sagittal fixtures (tools/kin/derive_fukuchi.py).

Needs only the Python standard library. Regenerate:

    pip download --no-deps --no-binary=:all: gaitkit==1.5.0   # or copy the sdist from pip's cache
    tar xzf gaitkit-1.5.0.tar.gz
    python3 tools/frontal/derive_frontal.py gaitkit-1.5.0/src/gaitkit/data

which writes tests/data/frontal/<trial>_<view>/ for trial in {fukuchi2018, gaitkit_pd} and view in
{anterior, posterior}. With `--noise-px SIGMA --seed N --out DIR` it adds Gaussian noise to the image
coordinates and writes to DIR instead (see `add_noise`). Every file and convention is described in
tests/data/frontal/README.md.

Lab frame (as in the gaitkit files): x = walking direction (+x), y = up, z = mediolateral, right at +z; mm.
"""
import argparse
import json
import math
import random
from pathlib import Path

# Trial name in tests/data -> (file in gaitkit's data folder, DeepLabCut scorer).
TRIALS = {
    "fukuchi2018": ("example_healthy.json", "fukuchi2018_mocap"),
    "gaitkit_pd": ("example_parkinson.json", "gaitkit_pd_mocap"),
}
VIEWS = ("anterior", "posterior")
JOINTS = ["shoulder", "hip", "knee", "ankle", "heel", "toe"]
NAMES = [f"{s}_{j}" for j in JOINTS for s in ("left", "right")]

WIDTH, HEIGHT = 1920, 1080
FOCAL_PX = 1400.0
CAMERA_HEIGHT_MM = 1000.0
NEAR_MM = 3000.0
FAR_MM = 8000.0
# A trial is too short to span NEAR..FAR: the nearest pelvis distance wins and the farthest follows.

# Two consecutive annotated heel strikes of one foot closer than this are two labels of one contact
# (Fukuchi's left 163/177: the file merges LHS and LON labels), not a stride.
MIN_STRIDE_S = 0.4

# Winter (2009), Biomechanics and Motor Control of Human Movement, fig. 4.1: shoulder (acromion)
# at 0.818 H, hip (greater trochanter) at 0.530 H, ankle (lateral malleolus) at 0.039 H. A trial
# without shoulder markers gets its trunk length from its leg length through these proportions,
# only to size the noise of `--noise-px`.
TRUNK_PER_LEG = (0.818 - 0.530) / (0.530 - 0.039)


def sub(a, b):
    return [a[i] - b[i] for i in range(len(a))]


def mid(a, b):
    return [(a[i] + b[i]) / 2 for i in range(len(a))]


def norm(a):
    return math.sqrt(sum(c * c for c in a))


def has_marker(frames, name):
    """gaitkit writes (0, 0, 0) for a landmark its extractor does not read (Fukuchi's shoulders)."""
    return any(any(c != 0.0 for c in f["landmark_positions"][name]) for f in frames)


class Camera:
    """Pinhole camera with a horizontal optical axis along -x (anterior) or +x (posterior)."""

    def __init__(self, view, pelvis_x, line_z, floor_y):
        self.forward = -1.0 if view == "anterior" else 1.0
        # The nearest pelvis position is NEAR_MM in front of the camera: the last frame when the
        # walker approaches (anterior), the first when the walker walks away (posterior).
        if view == "anterior":
            self.x = max(pelvis_x) + NEAR_MM
        else:
            self.x = min(pelvis_x) - NEAR_MM
        self.y = floor_y + CAMERA_HEIGHT_MM
        self.z = line_z

    def depth(self, p):
        return (p[0] - self.x) * self.forward

    def project(self, p):
        """Image (u right, v down) of lab point p. Facing -x with y up, the image right is -z
        (forward x up = (0, 0, -1)); facing +x it is +z."""
        d = self.depth(p)
        assert d > 0, "point behind the camera"
        right = (p[2] - self.z) * self.forward
        up = p[1] - self.y
        return (WIDTH / 2 + FOCAL_PX * right / d, HEIGHT / 2 - FOCAL_PX * up / d)


def frontal(p):
    """Orthographic projection onto the lab frontal plane: (mediolateral z, up y)."""
    return (p[2], p[1])


def cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def dot2(a, b):
    return a[0] * b[0] + a[1] * b[1]


def frontal_angles(lm, with_trunk):
    """Reference angles (degrees) of one frame, by the sign rules of tests/data/frontal/README.md.

    In the (z, y) plane a counter-clockwise turn moves a downward vector toward +z, the right side;
    `s` is +1 for the right leg and -1 for the left, so -s * cross is positive toward the leg's
    medial side and s * (z component) positive toward its own side."""
    out = {}
    f = {n: frontal(v) for n, v in lm.items()}
    if with_trunk:
        trunk = sub(mid(f["left_shoulder"], f["right_shoulder"]), mid(f["left_hip"], f["right_hip"]))
    for side, other, s in (("left", "right", -1.0), ("right", "left", 1.0)):
        if with_trunk:
            out[f"trunk_lean_{side}"] = math.degrees(math.atan2(s * trunk[0], trunk[1]))
        hip_line = sub(f[f"{side}_hip"], f[f"{other}_hip"])
        out[f"pelvic_obliquity_{side}"] = math.degrees(math.atan2(hip_line[1], s * hip_line[0]))
        # The hip line turned 90 degrees, whichever way points down.
        perp = (-hip_line[1], hip_line[0])
        if perp[1] > 0:
            perp = (-perp[0], -perp[1])
        thigh = sub(f[f"{side}_knee"], f[f"{side}_hip"])
        shank = sub(f[f"{side}_ankle"], f[f"{side}_knee"])
        out[f"hip_adduction_{side}"] = math.degrees(math.atan2(-s * cross2(perp, thigh), dot2(perp, thigh)))
        out[f"knee_varus_{side}"] = math.degrees(math.atan2(-s * cross2(thigh, shank), dot2(thigh, shank)))
    return out


def strides(hs, fps):
    """Consecutive heel strikes of one foot; of two labels closer than MIN_STRIDE_S the earlier is
    dropped, which in Fukuchi's left foot keeps 13, 177 and 340, labels of the same kind (each
    14-16 frames after the heel's contact, see tests/data/fukuchi2018/README.md)."""
    kept = []
    for i, fr in enumerate(hs):
        if i + 1 < len(hs) and (hs[i + 1] - fr) / fps < MIN_STRIDE_S:
            continue
        kept.append(fr)
    return list(zip(kept, kept[1:]))


def lateral_excursion(frames, side, start, end):
    """Largest distance (mm) of the ankle lateral of the horizontal (x, z) chord joining its positions
    at the two heel strikes; 0 if it never crosses to the lateral side."""
    s = 1.0 if side == "right" else -1.0
    a0 = frames[start]["landmark_positions"][f"{side}_ankle"]
    a1 = frames[end]["landmark_positions"][f"{side}_ankle"]
    dx, dz = a1[0] - a0[0], a1[2] - a0[2]
    length = math.hypot(dx, dz)
    nx, nz = -dz / length, dx / length
    if nz * s < 0:
        nx, nz = -nx, -nz
    best = 0.0
    for f in frames[start:end + 1]:
        p = f["landmark_positions"][f"{side}_ankle"]
        best = max(best, (p[0] - a0[0]) * nx + (p[2] - a0[2]) * nz)
    return best


def progression_normal(pelvis):
    """Unit (x, z) vector across the line of progression: perpendicular to the principal axis of
    the pelvis' horizontal path."""
    n = len(pelvis)
    mx = sum(p[0] for p in pelvis) / n
    mz = sum(p[2] for p in pelvis) / n
    sxx = sum((p[0] - mx) ** 2 for p in pelvis)
    szz = sum((p[2] - mz) ** 2 for p in pelvis)
    sxz = sum((p[0] - mx) * (p[2] - mz) for p in pelvis)
    a = 0.5 * math.atan2(2 * sxz, sxx - szz)
    return (-math.sin(a), math.cos(a))


def leg_length_mm(frames):
    total = 0.0
    for f in frames:
        lm = f["landmark_positions"]
        for side in ("left", "right"):
            total += norm(sub(lm[f"{side}_knee"], lm[f"{side}_hip"]))
            total += norm(sub(lm[f"{side}_ankle"], lm[f"{side}_knee"]))
    return total / (2 * len(frames))


def trunk_px(cam, lm, names, leg_mm):
    """Hip-to-shoulder size in pixels of one frame: the image distance between the mid-hip and the
    mid-shoulder, or, without shoulders, the trunk length from Winter's proportions at the pelvis
    depth."""
    hip = mid(lm["left_hip"], lm["right_hip"])
    if "left_shoulder" in names:
        sh = mid(lm["left_shoulder"], lm["right_shoulder"])
        a, b = cam.project(hip), cam.project(sh)
        return math.hypot(a[0] - b[0], a[1] - b[1])
    return FOCAL_PX * leg_mm * TRUNK_PER_LEG / cam.depth(hip)


def add_noise(image, sizes, sigma_px, rng):
    """Gaussian noise on every image coordinate; SIGMA is for a walker 100 px from hip to shoulder,
    so each frame gets SIGMA * (its hip-to-shoulder px / 100)."""
    for row, size in zip(image, sizes):
        sd = sigma_px * size / 100.0
        for n in row:
            u, v = row[n]
            row[n] = (u + rng.gauss(0.0, sd), v + rng.gauss(0.0, sd))


def write_keypoints(path, scorer, names, frames, image):
    rows = [
        ",".join(["scorer"] + [scorer] * (3 * len(names))),
        ",".join(["bodyparts"] + [n for n in names for _ in range(3)]),
        ",".join(["coords"] + ["x", "y", "likelihood"] * len(names)),
    ]
    for f, row in zip(frames, image):
        cells = [str(f["frame_index"])]
        for n in names:
            cells += [f"{row[n][0]:.3f}", f"{row[n][1]:.3f}", "1"]
        rows.append(",".join(cells))
    path.write_text("\n".join(rows) + "\n")


def write_events(path, gt, fps):
    ev = []
    for kind, key in (("heel_strike", "hs_frames"), ("toe_off", "to_frames")):
        for side in ("left", "right"):
            for fr in gt[key][side]:
                ev.append((fr, side, kind))
    ev.sort()
    lines = ["side,event,frame,time_s"] + [f"{s},{k},{fr},{fr / fps:.6f}" for fr, s, k in ev]
    path.write_text("\n".join(lines) + "\n")


def derive_trial(src, trial, scorer, out_root, noise, rng):
    d = json.loads(Path(src).read_text())
    fps = float(d["fps"])
    frames = d["angle_frames"]
    for i, f in enumerate(frames):
        assert f["frame_index"] == i, "frames must be 0..n-1 so that event frames index them"
    with_trunk = has_marker(frames, "left_shoulder") and has_marker(frames, "right_shoulder")
    names = [n for n in NAMES if with_trunk or "shoulder" not in n]
    first, last = frames[0]["landmark_positions"], frames[-1]["landmark_positions"]
    assert last["left_hip"][0] > first["left_hip"][0], "expected a walk along +x"
    assert first["right_hip"][2] > first["left_hip"][2], "expected the right side at +z"

    pelvis = [mid(f["landmark_positions"]["left_hip"], f["landmark_positions"]["right_hip"]) for f in frames]
    line_z = sum(p[2] for p in pelvis) / len(pelvis)
    # The heel marker sits above the floor by its radius and the heel pad; the floor can be no
    # higher than the lowest heel-marker reading, which we take as the floor.
    floor_y = min(f["landmark_positions"][f"{s}_heel"][1] for f in frames for s in ("left", "right"))
    leg_mm = leg_length_mm(frames)
    gt = d["ground_truth"]
    summary = {"trial": trial, "frames": len(frames), "fps": fps, "with_trunk": with_trunk,
               "line_z_mm": line_z, "floor_y_mm": floor_y, "leg_length_cm": leg_mm / 10}

    # View-independent outputs: reference angles, step widths, circumduction.
    ref_cols = ([f"trunk_lean_{s}" for s in ("left", "right")] if with_trunk else []) + [
        f"{a}_{s}" for a in ("pelvic_obliquity", "hip_adduction", "knee_varus") for s in ("left", "right")]
    ref_lines = ["frame," + ",".join(ref_cols)]
    ranges = {c: [math.inf, -math.inf] for c in ref_cols}
    for f in frames:
        ang = frontal_angles(f["landmark_positions"], with_trunk)
        for c in ref_cols:
            ranges[c] = [min(ranges[c][0], ang[c]), max(ranges[c][1], ang[c])]
        ref_lines.append(str(f["frame_index"]) + "," + ",".join(f"{ang[c]:.4f}" for c in ref_cols))
    summary["angle_ranges"] = ranges

    # Step width is taken across the line of progression (the pelvis' path, fitted), not along
    # the lab's z axis: the walkers' paths run 1.2 deg (healthy) and -2.1 deg (Parkinson's) off
    # the lab's x axis, which with the heels 0.6-0.7 m apart along the walk moves a z distance
    # by up to 1.5 cm.
    n = progression_normal(pelvis)
    step_lines = ["side,frame,step_width_cm,step_width_leg"]
    widths = []
    hs_all = sorted((fr, side) for side in ("left", "right") for fr in gt["hs_frames"][side])
    for fr, side in hs_all:
        other = "right" if side == "left" else "left"
        lm = frames[fr]["landmark_positions"]
        d = sub(lm[f"{side}_heel"], lm[f"{other}_heel"])
        w = abs(d[0] * n[0] + d[2] * n[1])
        widths.append(w / 10)
        step_lines.append(f"{side},{fr},{w / 10:.3f},{w / leg_mm:.5f}")
    summary["step_width_cm"] = widths

    circ_lines = ["side,start,end,circumduction_cm,circumduction_leg"]
    circs = []
    for side in ("left", "right"):
        for a, b in strides(sorted(gt["hs_frames"][side]), fps):
            c = lateral_excursion(frames, side, a, b)
            circs.append((side, a, b, round(c / 10, 2)))
            circ_lines.append(f"{side},{a},{b},{c / 10:.3f},{c / leg_mm:.5f}")
    summary["circumduction_cm"] = circs

    summary["views"] = {}
    for view in VIEWS:
        cam = Camera(view, [p[0] for p in pelvis], line_z, floor_y)
        image = [{n: cam.project(f["landmark_positions"][n]) for n in names} for f in frames]
        for f, row in zip(frames, image):
            # The subject's left must appear on the image right when facing the camera, on the
            # image left when seen from behind.
            for j in ("hip",) + (("shoulder",) if with_trunk else ()):
                lu, ru = row[f"left_{j}"][0], row[f"right_{j}"][0]
                if view == "anterior":
                    assert lu > ru, f"{trial} {view} frame {f['frame_index']}: left {j} not on image right"
                else:
                    assert lu < ru, f"{trial} {view} frame {f['frame_index']}: left {j} not on image left"
        placed = "image right" if view == "anterior" else "image left"
        checked = "hips and shoulders" if with_trunk else "hips"
        summary.setdefault("placement", []).append(
            f"{view}: left {checked} on the {placed} in all {len(frames)} frames (asserted)")
        sizes = [trunk_px(cam, f["landmark_positions"], names, leg_mm) for f in frames]
        if noise is not None:
            add_noise(image, sizes, noise, rng)
        depths = [cam.depth(p) for p in pelvis]
        near_i = min(range(len(frames)), key=lambda i: depths[i])
        far_i = max(range(len(frames)), key=lambda i: depths[i])
        us = [row[n][0] for row in image for n in names]
        vs = [row[n][1] for row in image for n in names]
        summary["views"][view] = {
            "camera_x_mm": cam.x, "camera_y_mm": cam.y, "camera_z_mm": cam.z,
            "pelvis_depth_near_m": depths[near_i] / 1000, "pelvis_depth_far_m": depths[far_i] / 1000,
            "near_frame": near_i, "far_frame": far_i,
            "trunk_px_near": sizes[near_i], "trunk_px_far": sizes[far_i],
            "u_range": (min(us), max(us)), "v_range": (min(vs), max(vs)),
        }
        out = Path(out_root) / f"{trial}_{view}"
        out.mkdir(parents=True, exist_ok=True)
        write_keypoints(out / "keypoints.csv", scorer, names, frames, image)
        write_events(out / "events.csv", gt, fps)
        (out / "reference.csv").write_text("\n".join(ref_lines) + "\n")
        (out / "steps.csv").write_text("\n".join(step_lines) + "\n")
        (out / "circumduction.csv").write_text("\n".join(circ_lines) + "\n")
        (out / "subject.json").write_text(json.dumps({"leg_length_cm": round(leg_mm / 10, 3), "fps": fps}) + "\n")
    return summary


def report(s):
    print(f"== {s['trial']}: {s['frames']} frames at {s['fps']} Hz, shoulders: {s['with_trunk']}, "
          f"walking line z = {s['line_z_mm']:.1f} mm, floor y = {s['floor_y_mm']:.1f} mm, "
          f"leg length {s['leg_length_cm']:.2f} cm")
    for c, (lo, hi) in s["angle_ranges"].items():
        print(f"   {c:24s} {lo:8.2f} .. {hi:7.2f} deg")
    print("   step widths (cm):", ", ".join(f"{w:.1f}" for w in s["step_width_cm"]))
    print("   circumduction (side, start, end, cm):", s["circumduction_cm"])
    for line in s["placement"]:
        print("  ", line)
    for view, v in s["views"].items():
        print(f"   {view}: camera at x={v['camera_x_mm']:.0f} y={v['camera_y_mm']:.0f} z={v['camera_z_mm']:.0f} mm; "
              f"pelvis {v['pelvis_depth_near_m']:.2f} m (frame {v['near_frame']}) .. "
              f"{v['pelvis_depth_far_m']:.2f} m (frame {v['far_frame']}); hip-to-shoulder "
              f"{v['trunk_px_near']:.0f} px near, {v['trunk_px_far']:.0f} px far; "
              f"u {v['u_range'][0]:.0f}..{v['u_range'][1]:.0f}, v {v['v_range'][0]:.0f}..{v['v_range'][1]:.0f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data_dir", help="gaitkit-1.5.0/src/gaitkit/data")
    ap.add_argument("--out", help="output folder (required with --noise-px)")
    ap.add_argument("--noise-px", type=float, help="noise SD in px for a 100 px hip-to-shoulder walker")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.noise_px is not None and not args.out:
        ap.error("--noise-px needs --out: noisy files do not belong in tests/data/frontal")
    out = args.out or str(Path(__file__).resolve().parents[2] / "tests" / "data" / "frontal")
    rng = random.Random(args.seed)
    for trial, (fname, scorer) in TRIALS.items():
        report(derive_trial(Path(args.data_dir) / fname, trial, scorer, out, args.noise_px, rng))


if __name__ == "__main__":
    main()
