"""Terminal swing impact for plant.py: the knee thrown into extension late in each swing.

The shank and foot (ankle, heel, toe) are re-timed against the thigh: from the swing's most flexed knee
to its heel strike, the frame at t shows the shank and foot where the thigh carried them at
tau(t) = m + (hs - m) * clamp((u - a) / (1 - a), 0, 1), u = (t - m) / (hs - m), a = 1 - 1 / k. The knee
stays flexed for the first part of that window and then extends k times as fast as the walker did, into
the same heel strike. Positions are taken in a thigh-fixed frame (origin the knee, axes the thigh and the
lab's mediolateral axis), so hip, thigh and knee do not move and the knee angle at t is the one at tau.
"""
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "frontal"))
import derive_frontal as df  # noqa: E402

SHANK = ("ankle", "heel", "toe")


def _unit(v):
    n = df.norm(v)
    return [x / n for x in v]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _frame(lm, side):
    """Thigh-fixed axes at a frame: e1 along the thigh (knee -> hip), e3 the lab's z made
    perpendicular to it, e2 = e3 x e1."""
    e1 = _unit(df.sub(lm[f"{side}_hip"], lm[f"{side}_knee"]))
    z = [0.0, 0.0, 1.0]
    e3 = _unit([z[i] - _dot(z, e1) * e1[i] for i in range(3)])
    return e1, _cross(e3, e1), e3


def _local(lm, side, name):
    e = _frame(lm, side)
    v = df.sub(lm[f"{side}_{name}"], lm[f"{side}_knee"])
    return [_dot(v, ax) for ax in e]


def _knee_angle(lm, side):
    a = df.sub(lm[f"{side}_knee"], lm[f"{side}_hip"])
    b = df.sub(lm[f"{side}_ankle"], lm[f"{side}_knee"])
    c = _dot(a, b) / (df.norm(a) * df.norm(b))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def terminal_impact(lms, side, swings, k):
    """Re-times each complete swing of `side` (see the module docs) with speed-up `k`; returns the
    [most flexed frame, heel strike] of each swing changed."""
    base = [dict(lm) for lm in lms]
    n = len(lms)
    a = 1.0 - 1.0 / k
    spans = []
    for to, hs in swings:
        if to < 0 or hs > n - 1:
            continue
        m = max(range(to, hs + 1), key=lambda i: _knee_angle(base[i], side))
        if hs - m < 3:
            continue
        spans.append([m, hs])
        for t in range(m, hs + 1):
            u = (t - m) / (hs - m)
            tau = m + (hs - m) * min(max((u - a) / (1.0 - a), 0.0), 1.0)
            i0 = min(int(math.floor(tau)), hs - 1)
            f = tau - i0
            e = _frame(base[t], side)
            for name in SHANK:
                p0, p1 = _local(base[i0], side, name), _local(base[i0 + 1], side, name)
                loc = [p0[j] + (p1[j] - p0[j]) * f for j in range(3)]
                knee = base[t][f"{side}_knee"]
                lms[t][f"{side}_{name}"] = [knee[j] + sum(loc[q] * e[q][j] for q in range(3)) for j in range(3)]
    return spans


def peak_extension_speed(lms, side, swings, fps):
    """The knee's fastest extension in each complete swing (deg/s), mean over swings."""
    out = []
    for to, hs in swings:
        if to < 0 or hs > len(lms) - 1:
            continue
        ang = [_knee_angle(lms[i], side) for i in range(to, hs + 1)]
        out.append(max((ang[i] - ang[i + 1]) * fps for i in range(len(ang) - 1)))
    return sum(out) / len(out) if out else float("nan")
