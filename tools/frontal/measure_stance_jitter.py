#!/usr/bin/env python3
"""The pose model's jitter at the knees and feet (issues 38 and 39), where measure_jitter.py
cannot see it: over a walk the feet move too fast for a 9-frame fit, but a foot in stance
stands still on the floor. For each stance of a run (heel strike + 2 to toe-off - 3 frames, from
its events.csv), the stance leg's keypoints (whichever of left/right lies nearer the stance's
median ankle, so a frame with the labels exchanged still counts) are fitted by a local quadratic
over 7 frames; the residuals, scaled to the white noise they imply, are summarised robustly (1.4826
x the median absolute deviation: where the swing foot passes the stance foot the pose model draws
them on one another, and those frames are errors, not jitter; how many lie beyond 3 MADs is
printed). Values in px and per 100 px of leg (hip-knee-ankle), as the test noise model takes
them (crates/gait-kin/tests/jitter).

    python3 tools/frontal/measure_stance_jitter.py RUN/keypoints.csv RUN/events.csv

Pure Python (no numpy) so it runs wherever tools/test.sh does."""
import csv
import math
import pathlib
import statistics
import sys

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from measure_jitter import residuals  # noqa: E402

HALF = 3  # 7-frame window: a stance at 30 fps is 18-21 frames
PARTS = ["hip", "knee", "ankle", "heel", "toe"]


def robust_sd(r):
    m = statistics.median(r)
    return 1.4826 * statistics.median(abs(v - m) for v in r)


def main():
    kp_path, ev_path = sys.argv[1], sys.argv[2]
    rows = list(csv.reader(open(kp_path)))
    names, coords = rows[1], rows[2]
    data = {int(r[0]): r for r in rows[3:]}
    index = {(names[k], coords[k]): k for k in range(1, len(names))}

    def val(f, name, c):
        v = data[f][index[(name, c)]] if f in data else ""
        return float(v) if v else math.nan

    def dist(f, a, b):
        return math.hypot(val(f, a, "x") - val(f, b, "x"), val(f, a, "y") - val(f, b, "y"))

    events = list(csv.DictReader(open(ev_path)))
    stances = []
    for side in ("left", "right"):
        hs = sorted(int(e["frame"]) for e in events if e["side"] == side and e["event"] == "heel_strike")
        to = sorted(int(e["frame"]) for e in events if e["side"] == side and e["event"] == "toe_off")
        for h in hs:
            t = next((x for x in to if x > h), None)
            if t is not None and (t - 3) - (h + 2) + 1 >= 2 * HALF + 2:
                stances.append((side, list(range(h + 2, t - 2))))
    legs = [dist(f, f"{s}_hip", f"{s}_knee") + dist(f, f"{s}_knee", f"{s}_ankle")
            for s, frames in stances for f in frames]
    leg = statistics.median(v for v in legs if not math.isnan(v))
    print(f"{kp_path}: {len(stances)} stances, leg {leg:.0f} px")
    res = {(p, c): [] for p in PARTS for c in "xy"}
    for side, frames in stances:
        other = "right" if side == "left" else "left"
        mx = statistics.median(val(f, f"{side}_ankle", "x") for f in frames)
        my = statistics.median(val(f, f"{side}_ankle", "y") for f in frames)

        def near(f, s):
            return math.hypot(val(f, f"{s}_ankle", "x") - mx, val(f, f"{s}_ankle", "y") - my)

        pick = {f: side if not near(f, other) < near(f, side) else other for f in frames}
        for p in PARTS:
            for c in "xy":
                x = [val(f, f"{pick[f]}_{p}", c) for f in frames]
                if not any(math.isnan(v) for v in x):
                    res[(p, c)].extend(residuals(x, HALF))
    for p in PARTS:
        for c in "xy":
            r = res[(p, c)]
            if len(r) < 10:
                continue
            sd = robust_sd(r)
            out = sum(abs(v - statistics.median(r)) > 3 * sd for v in r)
            print(f"  {p:6s} {c}: {sd:.2f} px ({sd / leg * 100:.2f} per 100 px of leg), "
                  f"{len(r)} residuals, {out} beyond 3 MADs")


if __name__ == "__main__":
    main()
