#!/usr/bin/env python3
"""Reference outputs of scipy's Butterworth design, filtfilt and CubicSpline for gait-kin's tests.

Needs: numpy==2.2.6 scipy==1.14.1 (Python 3.11). Regenerate from the repository root:

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install numpy==2.2.6 scipy==1.14.1
    /tmp/venv/bin/python tools/kin/make_scipy_fixtures.py crates/gait-kin/tests/fixtures

Writes butterworth.json (coefficients of butter(N, fc, fs=fs) and filtfilt(b, a, x) with the default
odd padding, padlen = 3 * max(len(a), len(b))) and spline.json (CubicSpline(t_valid, y_valid) with the
default not-a-knot end conditions, evaluated at the missing samples, as gait-kin's gap filler uses it).
Inputs are seeded pseudo-random walking-like signals, so the files are reproducible.
"""
import json
import sys
from pathlib import Path

import numpy as np
import scipy
from scipy.interpolate import CubicSpline
from scipy.signal import butter, filtfilt


def signal(rng, n, fs):
    t = np.arange(n) / fs
    return (300 + 40 * np.sin(2 * np.pi * 0.9 * t) + 15 * np.sin(2 * np.pi * 2.7 * t + 1)
            + rng.normal(0, 3, n)).tolist()


def main(out_dir):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(20261122)
    cases = []
    for order, fc, fs, n in [(4, 6.0, 30.0, 120), (4, 6.0, 150.0, 374), (2, 3.0, 25.0, 60),
                             (4, 6.0, 60.0, 16), (6, 10.0, 100.0, 200), (1, 2.0, 30.0, 40)]:
        b, a = butter(order, fc, fs=fs)
        x = signal(rng, n, fs)
        y = filtfilt(b, a, np.array(x))
        cases.append({"order": order, "cutoff_hz": fc, "fs": fs, "b": b.tolist(), "a": a.tolist(),
                      "x": x, "y": y.tolist()})
    (out / "butterworth.json").write_text(json.dumps(
        {"scipy": scipy.__version__, "cases": cases}))

    splines = []
    for n, holes in [(80, [(5, 9), (20, 21), (40, 47), (60, 62)]), (30, [(1, 3)]),
                     (12, [(4, 8)]), (7, [(2, 3)]), (5, [(1, 2)]), (50, [(10, 30)])]:
        t = np.arange(n, dtype=float)
        y = np.array(signal(rng, n, 30.0))
        valid = np.ones(n, bool)
        for s, e in holes:
            valid[s:e] = False
        cs = CubicSpline(t[valid], y[valid])
        missing = np.flatnonzero(~valid)
        y_in = [float(v) if ok else None for v, ok in zip(y, valid)]
        splines.append({"y": y_in, "missing": missing.tolist(), "filled": cs(t[missing]).tolist()})
    (out / "spline.json").write_text(json.dumps({"scipy": scipy.__version__, "cases": splines}))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
