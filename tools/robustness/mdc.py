"""Minimal detectable change (issue 37): for each reported measure, the smallest difference
between two analyses of the same walk that re-encoding and keypoint noise alone do not produce.

Each variant of the matrix and each noise seed is one more measurement of the same walk. With
the measure's values x_1..x_k (the original's and each repeat's), the standard error of
measurement is SEM = SD(x) and MDC95 = 1.96 * sqrt(2) * SEM, the usual test-retest definition
(two measurements, 95 % confidence). Measures: the spatiotemporal parameters and symmetry
indices (spatiotemporal.csv), each joint's peak flexion, extension and range of motion over
the mean cycle (cycles.csv), per side, and each checklist item's measure (checklist.csv, as
`checklist ITEM SIDE (UNIT)`; not those in image pixels), which `gait progress` floors its calls
with."""
import csv
import math
import pathlib

import compare


def measures(folder, fps, offset_s=0.0, mirrored=False, scale=1.0):
    """name -> value for one result folder (on the original's sides and pixels)."""
    r = compare.load(folder, fps, offset_s, mirrored, scale)
    out = {}
    for (param, side), (v, unit) in r.params.items():
        if math.isfinite(v):
            out[f"{param} {side} ({unit})"] = v
    for (side, joint), curve in r.curves.items():
        vals = [v for v in curve if math.isfinite(v)]
        if len(vals) == len(curve) and vals:
            out[f"{side} {joint} peak flexion (deg)"] = max(vals)
            out[f"{side} {joint} peak extension (deg)"] = min(vals)
            out[f"{side} {joint} range (deg)"] = max(vals) - min(vals)
    out.update(checklist(folder, mirrored))
    return out


def checklist(folder, mirrored=False):
    """`checklist ITEM SIDE (UNIT)` -> value for the items checklist.csv judged (any verdict)."""
    path = pathlib.Path(folder) / "checklist.csv"
    if not path.exists():
        return {}
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            v = compare.num(r["value"])
            if not math.isfinite(v) or r["unit"].startswith("px"):
                continue
            side = compare.OTHER.get(r["side"], r["side"]) if mirrored else r["side"]
            out[f"checklist {r['item']} {side} ({r['unit']})"] = v
    return out


def table(samples):
    """Rows (measure, n, sd, mdc95) over a list of `measures` dicts, measures seen in >= 3."""
    names = sorted({k for s in samples for k in s})
    rows = []
    for k in names:
        xs = [s[k] for s in samples if k in s]
        if len(xs) < 3:
            continue
        m = sum(xs) / len(xs)
        sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))
        rows.append((k, len(xs), sd, 1.96 * math.sqrt(2.0) * sd))
    return rows


def markdown(rows):
    out = ["| measure | repeats | SD | MDC95 |", "| --- | --- | --- | --- |"]
    out += [f"| {k} | {n} | {sd:.2f} | {mdc:.2f} |" for k, n, sd, mdc in rows]
    return "\n".join(out) + "\n"


def write_csv(rows, path):
    lines = ["measure,repeats,sd,mdc95"] + [f"\"{k}\",{n},{sd:.4f},{mdc:.4f}" for k, n, sd, mdc in rows]
    pathlib.Path(path).write_text("\n".join(lines) + "\n")
