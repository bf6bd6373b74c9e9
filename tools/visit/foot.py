"""Foot slap for plant.py: the planted foot turned toe-down about its heel in loading response."""
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "frontal"))
import derive_frontal as df  # noqa: E402

# Loading response is the first 0-12 % of the cycle, and gait's foot slap measure looks at 0-15 %: with
# stance about 60 % of the cycle, that is the first quarter of the stance.
LOADING_SHARE_OF_STANCE = 0.25


def loading_weights(n, stances):
    """Per-frame weight: a half sine over the first quarter of each stance (0 at the heel strike, 1
    in the middle of loading response, 0 again by 15 % of the cycle)."""
    w = [0.0] * n
    for a, b in stances:
        end = a + LOADING_SHARE_OF_STANCE * (b - a)
        for i in range(max(a, 0), min(int(math.ceil(end)), n - 1) + 1):
            if a <= i <= end and end > a:
                w[i] = max(w[i], math.sin(math.pi * (i - a) / (end - a)))
    return w


def foot_slap(lms, side, w, size, forward):
    """The toe marker of `side` turned toe-down about the heel in the walking plane by `size` deg
    times the weight: a foot that drops into plantarflexion after its heel strike (the ankle and the
    heel stay where they were, so the shank does not move)."""
    for lm, k in zip(lms, w):
        if k == 0:
            continue
        a = math.radians(size * k) * forward
        heel = lm[f"{side}_heel"]
        v = df.sub(lm[f"{side}_toe"], heel)
        # (x, y) turned by a: a forward vector (forward, 0) goes to (cos a, -sin a) * forward: down.
        x = v[0] * math.cos(a) + v[1] * math.sin(a)
        y = -v[0] * math.sin(a) + v[1] * math.cos(a)
        lm[f"{side}_toe"] = [heel[0] + x, heel[1] + y, heel[2] + v[2]]


def foot_pitch_deg(lm, side, forward):
    """The foot's (heel -> toe) angle below the horizontal in the walking plane, toe down positive."""
    v = df.sub(lm[f"{side}_toe"], lm[f"{side}_heel"])
    return math.degrees(math.atan2(-v[1], forward * v[0]))


def whip_weights(n, stances):
    """Per-frame weight: a half sine from 15 % of the stride before each toe-off to 5 % after it, the
    window gait's whip measure searches (the stride from the stance's heel strike to the next)."""
    w = [0.0] * n
    starts = [a for a, _ in stances]
    for k, (a, b) in enumerate(stances):
        stride = (starts[k + 1] - a) if k + 1 < len(starts) else (b - a) / 0.6
        lo, hi = b - 0.15 * stride, b + 0.05 * stride
        for i in range(max(int(math.floor(lo)), 0), min(int(math.ceil(hi)), n - 1) + 1):
            if lo <= i <= hi:
                w[i] = max(w[i], math.sin(math.pi * (i - lo) / (hi - lo)))
    return w


def whip(lms, side, w, shift_mm):
    """The heel of `side` moved sideways by `shift_mm` (+z) times the weight, the ankle by three
    quarters of it (it sits a quarter of the way from the heel to the forefoot the foot turns
    about); the toe and the leg above stay."""
    for lm, k in zip(lms, w):
        if k == 0:
            continue
        lm[f"{side}_heel"] = [lm[f"{side}_heel"][0], lm[f"{side}_heel"][1], lm[f"{side}_heel"][2] + shift_mm * k]
        lm[f"{side}_ankle"] = [lm[f"{side}_ankle"][0], lm[f"{side}_ankle"][1],
                               lm[f"{side}_ankle"][2] + 0.75 * shift_mm * k]


def whip_cm(lms, side, stances):
    """The heel's largest sideways shift against the toe around each toe-off (the whip window) from
    its median at foot flat (15-30 % of the stride), mean over strides, cm (+z positive)."""
    n = len(lms)
    starts = [a for a, _ in stances]
    out = []
    for k, (a, b) in enumerate(stances[:-1]):
        stride = starts[k + 1] - a
        off = [lms[i][f"{side}_heel"][2] - lms[i][f"{side}_toe"][2] for i in range(n)]
        flat = sorted(off[i] for i in range(max(a + int(0.15 * stride), 0), min(a + int(0.3 * stride), n - 1) + 1))
        win = [off[i] for i in range(max(int(b - 0.15 * stride), 0), min(int(b + 0.05 * stride), n - 1) + 1)]
        if flat and win and a >= 0:
            base = flat[len(flat) // 2]
            out.append(max((x - base for x in win), key=abs) / 10)
    return sum(out) / len(out) if out else float("nan")


def weight_spans(w):
    """The [first, last] frames of each run of non-zero weight."""
    spans = []
    for i, k in enumerate(w):
        if k > 0 and (i == 0 or w[i - 1] == 0):
            spans.append([i, i])
        elif k > 0:
            spans[-1][1] = i
    return spans
