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
