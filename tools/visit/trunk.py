"""The trunk deviations of plant.py: shoulder markers turned about the mid-hip point."""
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "frontal"))
import derive_frontal as df  # noqa: E402


def trunk_lean(lms, w, size):
    """Shoulders turned about the mid-hip point around the walking (x) axis, toward +z (right)."""
    for lm, k in zip(lms, w):
        if k == 0:
            continue
        a = math.radians(size * k)  # +z (LATERAL = 1) is the right leg's side
        c = df.mid(lm["left_hip"], lm["right_hip"])
        for s in ("left", "right"):
            v = df.sub(lm[f"{s}_shoulder"], c)
            # (z, y) turned by a: an upward vector (0, 1) goes to (sin a, cos a), toward +z.
            z = v[2] * math.cos(a) + v[1] * math.sin(a)
            y = -v[2] * math.sin(a) + v[1] * math.cos(a)
            lm[f"{s}_shoulder"] = [c[0] + v[0], c[1] + y, c[2] + z]


def trunk_flexion(lms, size, forward):
    """Shoulders turned forward about the mid-hip point around the lateral (z) axis, all the
    time: a trunk bent forward by `size` deg more than the walker's own (both sides)."""
    a = math.radians(size) * forward
    for lm in lms:
        c = df.mid(lm["left_hip"], lm["right_hip"])
        for s in ("left", "right"):
            v = df.sub(lm[f"{s}_shoulder"], c)
            # (x, y) turned by a: an upward vector (0, 1) goes to (sin a, cos a), toward +x.
            x = v[0] * math.cos(a) + v[1] * math.sin(a)
            y = -v[0] * math.sin(a) + v[1] * math.cos(a)
            lm[f"{s}_shoulder"] = [c[0] + x, c[1] + y, c[2] + v[2]]


def trunk_flexion_deg(lm, forward):
    """The trunk's forward lean from the vertical in the walking plane (deg)."""
    v = df.sub(df.mid(lm["left_shoulder"], lm["right_shoulder"]), df.mid(lm["left_hip"], lm["right_hip"]))
    return math.degrees(math.atan2(forward * v[0], v[1]))
