#!/usr/bin/env python3
"""Plant amputee gait deviations of known size into two real motion-capture trials and project them
into four camera views, for the visit/checklist tests. tools/visit/README.md says exactly what moves,
when and by how much.

Sources: the trials of tools/frontal/derive_frontal.py (Fukuchi 2018 healthy, gaitkit's Parkinson's
trial) read straight from the `gaitkit==1.5.0` sdist, which `pip download` fetches into the cache
folder (default target/gaitkit-sdist/) the first time; its sha256 is checked. The projection, the
DeepLabCut writer and the frontal angles are derive_frontal.py's, imported, not copied.

    python3 tools/visit/plant.py --out target/planted [--cache target/gaitkit-sdist] [--data-dir DIR]

writes OUT/<trial>/{subject.json, events.csv, cases.json} and OUT/<trial>/<case>/{plant.json,
<view>/keypoints.csv} for view in {left, right, anterior, posterior}, and prints 3-D sanity figures
of every planted deviation. Standard library only.

Lab frame (as in the gaitkit files): x = walking direction (+x), y = up, z = mediolateral, right at
+z; mm.
"""
import argparse
import copy
import hashlib
import json
import math
import subprocess
import sys
import tarfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "frontal"))
import derive_frontal as df  # noqa: E402
from trunk import trunk_flexion, trunk_flexion_deg, trunk_lean  # noqa: E402
from foot import (foot_pitch_deg, foot_slap, loading_weights, weight_spans, whip, whip_cm,  # noqa: E402
                  whip_weights)
from knee import peak_extension_speed, terminal_impact  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
SDIST = ("gaitkit==1.5.0", "gaitkit-1.5.0.tar.gz",
         "de1f0c258152c5eac2e3d0382fb57e321c69091ee7923ce0849ff24d9640d861")
DATA_IN_SDIST = "gaitkit-1.5.0/src/gaitkit/data/"

PLANTED = "right"
OTHER = "left"
LATERAL = 1.0  # +z is lateral for the right leg
RAMP_S = 0.05
# 5 mm above its lowest point in the stance the toe marker has lifted: on the PD trial this lands
# within 2 frames of the annotated toe-offs (printed), and mocap markers do not jitter by that much.
TOE_LIFT_MM = 5.0
# A toe rising less than this after its lowest point is a drifting stance marker, not a swing (the
# PD walker's left toe clears its stance level by only 28 mm).
SWING_RISE_MM = 20.0
SIDE_VIEW_MIN_MM = 4000.0
SIDE_VIEW_MARGIN_PX = 100.0
VIEWS = ("left", "right", "anterior", "posterior")
LEG = ("knee", "ankle", "heel", "toe")
FOOT = ("ankle", "heel", "toe")

# case -> (deviation, size, unit)
CASES = {
    "none": ("none", 0, None),
    "trunk_lean_5": ("trunk_lean", 5, "deg"), "trunk_lean_10": ("trunk_lean", 10, "deg"),
    "wide_base_5": ("wide_base", 5, "cm"), "wide_base_10": ("wide_base", 10, "cm"),
    "circumduction_5": ("circumduction", 5, "cm"), "circumduction_10": ("circumduction", 10, "cm"),
    "hip_hike_5": ("hip_hike", 5, "deg"), "hip_hike_10": ("hip_hike", 10, "deg"),
    "vaulting_3": ("vaulting", 3, "cm"), "vaulting_6": ("vaulting", 6, "cm"),
    "knee_flexed_7": ("knee_flexed", 7, "deg"), "knee_flexed_15": ("knee_flexed", 15, "deg"),
    "short_stance_10": ("short_stance", 10, "percent"),
    "trunk_flexion_15": ("trunk_flexion", 15, "deg"),
    "foot_slap_15": ("foot_slap", 15, "deg"), "foot_slap_30": ("foot_slap", 30, "deg"),
    "medial_whip_3": ("medial_whip", 3, "cm"), "medial_whip_8": ("medial_whip", 8, "cm"),
    "terminal_impact_2": ("terminal_impact", 2, "x"), "terminal_impact_4": ("terminal_impact", 4, "x"),
}


# ---------------------------------------------------------------- sources

def fetch_sdist(cache):
    path = cache / SDIST[1]
    if not path.exists():
        cache.mkdir(parents=True, exist_ok=True)
        # --no-binary for gaitkit alone: with :all: pip would also build gaitkit's build dependencies
        # (numpy) from source just to prepare the metadata, which fails or takes minutes.
        subprocess.run([sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--no-binary", "gaitkit",
                        "--dest", str(cache), SDIST[0]], check=True)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != SDIST[2]:
        sys.exit(f"{path}: sha256 {digest}, expected {SDIST[2]}")
    return path


def load_trials(args):
    out = {}
    if args.data_dir:
        for trial, (fname, _) in df.TRIALS.items():
            out[trial] = json.loads((Path(args.data_dir) / fname).read_text())
        return out
    with tarfile.open(fetch_sdist(Path(args.cache))) as tar:
        for trial, (fname, _) in df.TRIALS.items():
            out[trial] = json.loads(tar.extractfile(DATA_IN_SDIST + fname).read())
    return out


# ---------------------------------------------------------------- vectors

def add(a, b):
    return [a[i] + b[i] for i in range(3)]


def scale(a, k):
    return [c * k for c in a]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def unit(a):
    return scale(a, 1.0 / df.norm(a))


def lerp(a, b, t):
    return [a[i] + (b[i] - a[i]) * t for i in range(3)]


def angle_deg(a, b):
    c = dot(a, b) / (df.norm(a) * df.norm(b))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def knee_flexion(lm, side):
    """Angle between thigh (hip -> knee) and shank (knee -> ankle) in 3-D: 0 for a straight leg."""
    return angle_deg(df.sub(lm[f"{side}_knee"], lm[f"{side}_hip"]), df.sub(lm[f"{side}_ankle"], lm[f"{side}_knee"]))


# ---------------------------------------------------------------- phases

def toe_lifts(frames, side, hs):
    """Toe-offs from the 3-D toe marker: in each span between heel strikes (and the trial's ends),
    the first frame after the toe's lowest point where it is TOE_LIFT_MM above it, if it then rises
    at least SWING_RISE_MM (a swing follows)."""
    n = len(frames)
    bounds = [0] + [h for h in hs if 0 < h < n - 1] + [n - 1]
    out = []
    for a, b in zip(bounds, bounds[1:]):
        y = [frames[i]["landmark_positions"][f"{side}_toe"][1] for i in range(a, b + 1)]
        m = min(range(len(y)), key=lambda i: y[i])
        if max(y[m:]) - y[m] < SWING_RISE_MM:
            continue
        out.append(a + next(i for i in range(m, len(y)) if y[i] > y[m] + TOE_LIFT_MM))
    return out


def side_phases(frames, gt, side, fps):
    """(stances, swings) as lists of (start, end) frames. Heel strikes are the annotated ones (labels
    closer than derive_frontal.MIN_STRIDE_S merged, as there); toe-offs come from the toe marker
    (`toe_lifts`) because Fukuchi's annotated right toe-offs fall in foot-flat (see
    tests/data/fukuchi2018/README.md). A phase cut by the trial's start or end gets the mean length
    of the complete phases of its kind, so its start or end may lie outside 0..n-1."""
    pairs = df.strides(sorted(gt["hs_frames"][side]), fps)
    hs = sorted({a for a, _ in pairs} | {b for _, b in pairs}) or sorted(gt["hs_frames"][side])
    to = toe_lifts(frames, side, hs)
    ev = sorted([(f, "hs") for f in hs] + [(f, "to") for f in to])
    for (_, k1), (_, k2) in zip(ev, ev[1:]):
        assert k1 != k2, f"{side}: two {k1} in a row: {ev}"
    stances, swings, cut = [], [], []
    for (f1, k1), (f2, _) in zip(ev, ev[1:]):
        (stances if k1 == "hs" else swings).append((f1, f2))
    n = len(frames)

    def mean_len(ph):
        return round(sum(b - a for a, b in ph) / len(ph))

    if ev[0][0] > 0:
        cut.append(("start", ev[0]))
    if ev[-1][0] < n - 1:
        cut.append(("end", ev[-1]))
    full_st, full_sw = list(stances), list(swings)
    for where, (f, k) in cut:
        # Before a heel strike the foot swings; after it, it stands.
        if where == "start":
            kind = swings if k == "hs" else stances
            ref = full_sw if k == "hs" else full_st
            kind.insert(0, (f - mean_len(ref), f))
        else:
            kind = stances if k == "hs" else swings
            ref = full_st if k == "hs" else full_sw
            kind.append((f, f + mean_len(ref)))
    return stances, swings, to


def plateau(n, phases, fps):
    """Per-frame weight: 0 outside the phases and at their events, 1 inside, raised-cosine ramps over
    the first and last RAMP_S of each phase."""
    r = round(RAMP_S * fps)
    w = [0.0] * n

    def ramp(k):
        return 0.5 - 0.5 * math.cos(math.pi * min(max(k, 0), r) / r)

    for a, b in phases:
        for i in range(max(a, 0), min(b, n - 1) + 1):
            w[i] = max(w[i], min(ramp(i - a), ramp(b - i)))
    return w


def half_sine(n, phases):
    w = [0.0] * n
    for a, b in phases:
        for i in range(max(a, 0), min(b, n - 1) + 1):
            w[i] = max(w[i], math.sin(math.pi * (i - a) / (b - a)))
    return w


def clipped(phases, n):
    return [[max(a, 0), min(b, n - 1)] for a, b in phases if b >= 0 and a <= n - 1]


# ---------------------------------------------------------------- deviations

def shift(lms, w, names_mm):
    for lm, k in zip(lms, w):
        if k == 0:
            continue
        for name, d in names_mm:
            lm[name] = add(lm[name], scale(d, k))


def lateral(mm):
    return [0.0, 0.0, LATERAL * mm]


def up(mm):
    return [0.0, mm, 0.0]


def hip_width_mm(frames):
    return sum(abs(f["landmark_positions"]["right_hip"][2] - f["landmark_positions"]["left_hip"][2])
               for f in frames) / len(frames)


def flex_knee(lms, w, size):
    """Hip and ankle stay; the knee moves along the forward direction perpendicular to the hip-ankle
    line until the thigh-shank angle has grown by size * w. With hip and ankle fixed no knee position
    that keeps both segment lengths changes that angle (such positions form a circle around the
    hip-ankle axis, all with the same angle), so the segments lengthen instead; returns the largest
    relative lengthening."""
    worst = 0.0
    side = PLANTED
    for lm, k in zip(lms, w):
        if k == 0:
            continue
        h, kn, a = lm[f"{side}_hip"], lm[f"{side}_knee"], lm[f"{side}_ankle"]
        target = knee_flexion(lm, side) + size * k
        u = unit(df.sub(a, h))
        fwd = unit(df.sub([1.0, 0.0, 0.0], scale(u, u[0])))

        def flex(t):
            p = add(kn, scale(fwd, t))
            return angle_deg(df.sub(p, h), df.sub(a, p))

        # The angle first falls while a knee behind the line comes forward, then grows; the first
        # millimetre past the target brackets the root.
        t = 0.0
        while flex(t) < target:
            t += 1.0
            assert t < 500, "knee flexion target not reached within 0.5 m"
        lo, hi = max(t - 1.0, 0.0), t
        for _ in range(40):
            m = (lo + hi) / 2
            lo, hi = (m, hi) if flex(m) < target else (lo, m)
        p = add(kn, scale(fwd, hi))
        worst = max(worst, df.norm(df.sub(p, h)) / df.norm(df.sub(kn, h)) - 1,
                    df.norm(df.sub(a, p)) / df.norm(df.sub(a, kn)) - 1)
        lm[f"{side}_knee"] = p
    return worst


def short_stance(frames, lms, stances, swings, to, fraction):
    """Time-warp the planted foot so that each complete stance ends `fraction` of its length early.
    Between mid-stance M and mid-swing W the output frame s shows the source instant tau(s), piecewise
    linear through (M, M), (TO - fraction * stance, TO), (W, W): the foot's late stance runs faster,
    its early swing slower, and nothing changes outside M..W. Ankle, heel and toe take their lab
    positions at tau (a standing foot stays where it stands); the hip stays; the knee is rebuilt from
    the hip, the warped ankle and the thigh and shank lengths at tau, in the leg's plane at tau.
    Returns the warped spans, the new toe-offs and the number of frames where hip and ankle ended up
    farther apart than thigh plus shank (the knee is then put on the straight line)."""
    n = len(frames)
    side = PLANTED
    spans, new_to = [], []
    straight = 0

    def at(name, t):
        i = min(int(math.floor(t)), n - 2)
        return lerp(frames[i]["landmark_positions"][name], frames[i + 1]["landmark_positions"][name], t - i)

    for hs, t_off in stances:
        if hs < 0 or t_off > n - 1 or t_off not in to:
            continue
        nxt = next((b for a, b in swings if a == t_off), None)
        m_st = (hs + t_off) / 2
        m_sw = min((t_off + nxt) / 2, n - 1)
        t_new = t_off - fraction * (t_off - hs)
        spans.append([math.ceil(m_st), math.floor(m_sw)])
        new_to.append(t_new)
        for s in range(math.ceil(m_st), math.floor(m_sw) + 1):
            if s <= t_new:
                tau = m_st + (s - m_st) * (t_off - m_st) / (t_new - m_st)
            else:
                tau = t_off + (s - t_new) * (m_sw - t_off) / (m_sw - t_new)
            lm = lms[s]
            for j in FOOT:
                lm[f"{side}_{j}"] = at(f"{side}_{j}", tau)
            h0, k0, a0 = at(f"{side}_hip", tau), at(f"{side}_knee", tau), at(f"{side}_ankle", tau)
            thigh, shank = df.norm(df.sub(k0, h0)), df.norm(df.sub(a0, k0))
            u0 = unit(df.sub(a0, h0))
            off = df.sub(df.sub(k0, h0), scale(u0, dot(df.sub(k0, h0), u0)))
            h, a = lm[f"{side}_hip"], lm[f"{side}_ankle"]
            d = df.norm(df.sub(a, h))
            u = unit(df.sub(a, h))
            e = unit(df.sub(off, scale(u, dot(off, u))))
            along = (d * d + thigh * thigh - shank * shank) / (2 * d)
            straight += thigh * thigh < along * along
            r = math.sqrt(max(thigh * thigh - along * along, 0.0))
            lm[f"{side}_knee"] = add(h, add(scale(u, along), scale(e, r)))
    return spans, new_to, straight


# ---------------------------------------------------------------- cameras

class SideCamera:
    """Pinhole camera with a horizontal optical axis along the mediolateral z axis, on the subject's
    left (looking +z) or right (looking -z), at the middle of the trial's pelvis travel. Image right =
    forward x up: +x from the right side (the walker walks to the image right), -x from the left."""

    def __init__(self, view, pelvis_x, line_z, floor_y, distance):
        self.forward = 1.0 if view == "left" else -1.0
        self.x = (min(pelvis_x) + max(pelvis_x)) / 2
        self.y = floor_y + df.CAMERA_HEIGHT_MM
        self.z = line_z - self.forward * distance

    def depth(self, p):
        return (p[2] - self.z) * self.forward

    def project(self, p):
        d = self.depth(p)
        assert d > 0, "point behind the camera"
        right = -(p[0] - self.x) * self.forward
        return (df.WIDTH / 2 + df.FOCAL_PX * right / d, df.HEIGHT / 2 - df.FOCAL_PX * (p[1] - self.y) / d)


def side_distance(frames, names, pelvis_x, line_z, floor_y):
    """SIDE_VIEW_MIN_MM, or the nearest half metre at which every keypoint of both side views lies at
    least SIDE_VIEW_MARGIN_PX inside the image, whichever is farther."""
    d = SIDE_VIEW_MIN_MM
    while True:
        ok = True
        for view in ("left", "right"):
            cam = SideCamera(view, pelvis_x, line_z, floor_y, d)
            for f in frames:
                for n in names:
                    u, v = cam.project(f["landmark_positions"][n])
                    m = SIDE_VIEW_MARGIN_PX
                    ok = ok and m <= u <= df.WIDTH - m and m <= v <= df.HEIGHT - m
        if ok:
            return d
        d += 500.0


def check_side_view(view, cam, lms, image):
    """The right view sees the walker walk to the image right with the right hip nearer and the right
    leg drawn larger; the left view mirrors it."""
    near, far = ("right", "left") if view == "right" else ("left", "right")
    hu = [(r["left_hip"][0] + r["right_hip"][0]) / 2 for r in image]
    assert (hu[-1] > hu[0]) == (view == "right"), f"{view}: walking the wrong way in the image"
    for lm in lms:
        assert cam.depth(lm[f"{near}_hip"]) < cam.depth(lm[f"{far}_hip"]), f"{view}: {near} hip not nearer"

    def leg_px(s):
        return sum(math.dist(r[f"{s}_hip"], r[f"{s}_knee"]) + math.dist(r[f"{s}_knee"], r[f"{s}_ankle"])
                   for r in image) / len(image)

    assert leg_px(near) > leg_px(far), f"{view}: {near} leg not drawn larger"
    return leg_px(near) / leg_px(far)


# ---------------------------------------------------------------- sanity measures

def mean(xs):
    xs = list(xs)
    return sum(xs) / len(xs) if xs else float("nan")


def added_step_mm(base, lms, names):
    """Largest frame-to-frame displacement the planting added to any keypoint: a jump would show here."""
    return max(math.dist(df.sub(lms[i + 1][x], lms[i][x]), df.sub(base[i + 1][x], base[i][x]))
               for i in range(len(lms) - 1) for x in names)


def full(w):
    return [i for i, k in enumerate(w) if k == 1.0]


def measure(dev, lms, ph, fps, with_trunk):
    """The 3-D measure of one deviation: (planted side, other side), both in the same convention."""
    st, sw = {s: plateau(len(lms), ph[s][0], fps) for s in ph}, {s: plateau(len(lms), ph[s][1], fps) for s in ph}
    wrapped = [{"landmark_positions": lm} for lm in lms]
    out = {}
    forward = 1.0 if lms[-1]["left_hip"][0] > lms[0]["left_hip"][0] else -1.0
    for s in ("right", "left"):
        if dev == "trunk_flexion" and with_trunk:
            out[s] = mean(trunk_flexion_deg(lms[i], forward) for i in full(st[s]))
        elif dev == "trunk_lean" and with_trunk:
            out[s] = mean(df.frontal_angles(lms[i], True)[f"trunk_lean_{s}"] for i in full(st[s]))
        elif dev == "wide_base":
            o = "left" if s == "right" else "right"
            out[s] = mean(abs(lms[h][f"{s}_heel"][2] - lms[h][f"{o}_heel"][2]) / 10
                          for h, _ in ph[s][0] if 0 <= h < len(lms))
        elif dev == "circumduction":
            hs = [a for a, _ in ph[s][0] if a >= 0]
            out[s] = mean(df.lateral_excursion(wrapped, s, a, b) / 10 for a, b in zip(hs, hs[1:]))
        elif dev == "hip_hike":
            out[s] = mean(df.frontal_angles(lms[i], False)[f"pelvic_obliquity_{s}"] for i in full(sw[s]))
        elif dev == "vaulting":
            # the heel of the foot standing while the other swings
            o = "left" if s == "right" else "right"
            out[s] = mean(lms[i][f"{o}_heel"][1] / 10 for i in full(sw[s]))
        elif dev == "knee_flexed":
            out[s] = mean(knee_flexion(lms[i], s) for i in full(st[s]))
        elif dev == "terminal_impact":
            out[s] = peak_extension_speed(lms, s, ph[s][1], fps)
        elif dev == "medial_whip":
            out[s] = whip_cm(lms, s, ph[s][0]) * (1.0 if s == "right" else -1.0) * LATERAL
        elif dev == "foot_slap":
            # the most toe-down foot in each loading response, averaged over the stances
            w = loading_weights(len(lms), ph[s][0])
            spans = [[i for i in range(max(a, 0), min(b, len(lms))) if w[i] > 0] for a, b in ph[s][0]]
            out[s] = mean(max(foot_pitch_deg(lms[i], s, forward) for i in sp) for sp in spans if sp)
        elif dev == "short_stance":
            hs = [a for a, _ in ph[s][0] if a >= 0]
            to = toe_lifts(wrapped, s, hs)
            out[s] = mean((t - h) / fps for h in hs for t in [min((t for t in to if t > h), default=None)]
                          if t is not None)
    return out


UNITS = {"trunk_lean": "deg toward the side, in its stance", "wide_base": "cm heel-to-heel at its heel strikes",
         "circumduction": "cm lateral excursion per stride", "hip_hike": "deg obliquity of its hip, in its swing",
         "vaulting": "cm height of the standing heel while it swings", "knee_flexed": "deg knee flexion in its stance",
         "short_stance": "s heel strike to toe lift",
         "trunk_flexion": "deg forward from the vertical, in its stance",
         "foot_slap": "deg toe-down foot, most in loading response",
         "medial_whip": "cm heel shift against the toe at toe-off, + lateral",
         "terminal_impact": "deg/s fastest knee extension in its swing"}


# ---------------------------------------------------------------- main

def plant_trial(trial, d, out_root):
    fps = float(d["fps"])
    frames = d["angle_frames"]
    n = len(frames)
    for i, f in enumerate(frames):
        assert f["frame_index"] == i, "frames must be 0..n-1 so that event frames index them"
    scorer = df.TRIALS[trial][1]
    gt = d["ground_truth"]
    with_trunk = df.has_marker(frames, "left_shoulder") and df.has_marker(frames, "right_shoulder")
    names = [x for x in df.NAMES if with_trunk or "shoulder" not in x]
    pelvis = [df.mid(f["landmark_positions"]["left_hip"], f["landmark_positions"]["right_hip"]) for f in frames]
    line_z = sum(p[2] for p in pelvis) / n
    floor_y = min(f["landmark_positions"][f"{s}_heel"][1] for f in frames for s in ("left", "right"))
    leg_mm = df.leg_length_mm(frames)
    pelvis_x = [p[0] for p in pelvis]
    dist = side_distance(frames, names, pelvis_x, line_z, floor_y)
    cams = {v: (SideCamera(v, pelvis_x, line_z, floor_y, dist) if v in ("left", "right")
                else df.Camera(v, pelvis_x, line_z, floor_y)) for v in VIEWS}

    ph = {s: side_phases(frames, gt, s, fps) for s in ("right", "left")}
    stances, swings, to = ph[PLANTED]
    print(f"== {trial}: {n} frames at {fps} Hz, shoulders: {with_trunk}, leg {leg_mm / 10:.2f} cm, "
          f"side cameras {dist / 1000:.1f} m from the walking line")
    for s in ("right", "left"):
        print(f"   {s}: stances {ph[s][0]}, swings {ph[s][1]}; toe lifts {ph[s][2]} "
              f"(annotated toe-offs {sorted(gt['to_frames'][s])})")

    root = Path(out_root) / trial
    root.mkdir(parents=True, exist_ok=True)
    (root / "subject.json").write_text(json.dumps({"leg_length_cm": round(leg_mm / 10, 3), "fps": fps}) + "\n")
    df.write_events(root / "events.csv", gt, fps)
    st_w = plateau(n, stances, fps)
    sw_w = plateau(n, swings, fps)
    sw_sine = half_sine(n, swings)
    hike_width = hip_width_mm(frames)
    written, skipped = [], {}
    base = [f["landmark_positions"] for f in frames]
    for case, (dev, size, unit_) in CASES.items():
        if dev in ("trunk_lean", "trunk_flexion") and not with_trunk:
            skipped[case] = "no shoulder markers in this trial (gaitkit writes them as 0, 0, 0)"
            continue
        lms = copy.deepcopy(base)
        spans = []
        note = ""
        if dev == "trunk_lean":
            trunk_lean(lms, st_w, size)
            spans = clipped(stances, n)
        elif dev == "trunk_flexion":
            trunk_flexion(lms, size, 1.0 if pelvis_x[-1] > pelvis_x[0] else -1.0)
            spans = [[0, n - 1]]
        elif dev == "wide_base":
            shift(lms, [1.0] * n, [(f"{PLANTED}_{j}", lateral(size * 10)) for j in FOOT]
                  + [(f"{PLANTED}_knee", lateral(size * 5))])
            spans = [[0, n - 1]]
        elif dev == "circumduction":
            shift(lms, sw_sine, [(f"{PLANTED}_{j}", lateral(size * 10)) for j in FOOT]
                  + [(f"{PLANTED}_knee", lateral(size * 5))])
            spans = clipped(swings, n)
        elif dev == "hip_hike":
            h = hike_width * math.tan(math.radians(size))
            shift(lms, sw_w, [(f"{PLANTED}_{j}", up(h)) for j in ("hip",) + LEG])
            spans = clipped(swings, n)
            note = f"raised {h:.1f} mm = mean hip-marker width {hike_width:.1f} mm x tan({size} deg)"
        elif dev == "vaulting":
            shift(lms, sw_w, [(f"{OTHER}_heel", up(size * 10)), (f"{OTHER}_ankle", up(size * 10 * 2 / 3))])
            spans = clipped(swings, n)
        elif dev == "knee_flexed":
            worst = flex_knee(lms, st_w, size)
            spans = clipped(stances, n)
            note = f"thigh and shank lengthened by at most {100 * worst:.1f} %"
        elif dev == "foot_slap":
            w = loading_weights(n, stances)
            foot_slap(lms, PLANTED, w, size, 1.0 if pelvis_x[-1] > pelvis_x[0] else -1.0)
            spans = weight_spans(w)
        elif dev == "terminal_impact":
            spans = terminal_impact(lms, PLANTED, swings, size)
        elif dev == "medial_whip":
            w = whip_weights(n, stances)
            whip(lms, PLANTED, w, -LATERAL * size * 10)
            spans = weight_spans(w)
        elif dev == "short_stance":
            spans, new_to, straight = short_stance(frames, lms, stances, swings, to, size / 100)
            moved = [[t, round(nt, 1)] for t, nt in zip([t for t in to if any(a <= t <= b for a, b in spans)], new_to)]
            note = "toe-offs " + ", ".join(f"{t} -> {nt}" for t, nt in moved)
            note += f"; straight-leg frames {straight}" if straight else ""
        cdir = root / case
        side = {"none": None, "trunk_flexion": "both"}.get(dev, PLANTED)
        plant = {"deviation": dev, "size": size, "unit": unit_, "side": side,
                 "frames": spans}
        if dev == "short_stance":
            plant["toe_offs"] = moved
        if note:
            plant["note"] = note
        for view in VIEWS:
            cam = cams[view]
            image = [{x: cam.project(lm[x]) for x in names} for lm in lms]
            for row in image:
                for u, v in row.values():
                    assert 0 <= u <= df.WIDTH and 0 <= v <= df.HEIGHT, f"{trial} {case} {view}: keypoint off the image"
            if view in ("left", "right") and case == "none":
                ratio = check_side_view(view, cam, lms, image)
                print(f"   {view} view: walks to the image {'right' if view == 'right' else 'left'}, {view} hip "
                      f"nearer in every frame, {view} leg drawn {ratio:.3f}x the other (asserted)")
            (cdir / view).mkdir(parents=True, exist_ok=True)
            df.write_keypoints(cdir / view / "keypoints.csv", scorer, names, frames, image)
        (cdir / "plant.json").write_text(json.dumps(plant) + "\n")
        written.append(case)
        if dev == "none":
            print(f"   {'case':18s} {'measure':45s} {'planted before':>14s} {'after':>8s} {'other before':>13s} "
                  f"{'after':>8s} {'step+':>6s}")
        else:
            before = measure(dev, base, ph, fps, with_trunk)
            after = measure(dev, lms, ph, fps, with_trunk)
            print(f"   {case:18s} {UNITS[dev]:45s} {before['right']:14.2f} {after['right']:8.2f} "
                  f"{before['left']:13.2f} {after['left']:8.2f} {added_step_mm(base, lms, names):6.1f}" + (f"   ({note})" if note else ""))
    for case, why in skipped.items():
        print(f"   {case:18s} skipped: {why}")
    (root / "cases.json").write_text(json.dumps({"written": written, "skipped": skipped}, indent=1) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="output folder, e.g. target/planted")
    ap.add_argument("--cache", default=str(REPO / "target" / "gaitkit-sdist"),
                    help="where the gaitkit sdist is kept (downloaded with pip when absent)")
    ap.add_argument("--data-dir", help="an unpacked gaitkit-1.5.0/src/gaitkit/data instead of the sdist")
    args = ap.parse_args()
    t0 = time.time()
    trials = load_trials(args)
    print(f"sources read in {time.time() - t0:.1f} s")
    for trial, d in trials.items():
        plant_trial(trial, d, args.out)
    print(f"done in {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
