"""Two results of the same walk compared in seconds (issue 37): events, bouts, accepted cycles,
mean curves and spatiotemporal parameters. A result is a folder written by `gait run` or
`gait kin`; a variant's times and sides are first mapped back onto the original's clock and
sides (its cut start, its mirror)."""
import csv
import dataclasses
import math
import pathlib

OTHER = {"left": "right", "right": "left"}
# Parameters whose values are lengths in the image: compared after scaling by the frame width.
PIXEL_UNITS = {"px", "px/s"}


def rows(path):
    p = pathlib.Path(path)
    if not p.exists():
        return []
    with open(p, newline="") as f:
        return list(csv.DictReader(f))


def num(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return math.nan


@dataclasses.dataclass
class Result:
    events: list  # (side, event, time_s)
    bouts: list  # (first_s, last_s)
    cycles: list  # accepted (side, start_s, end_s)
    rejected: list  # rejected (side, start_s, end_s, reasons)
    curves: dict  # (side, joint) -> [101 means]
    params: dict  # (parameter, side) -> (mean, unit)


def load(folder, fps, offset_s=0.0, mirrored=False, scale=1.0):
    """A result folder on the original's clock and sides; lengths in the original's pixels."""
    d = pathlib.Path(folder)
    side = (lambda s: OTHER.get(s, s)) if mirrored else (lambda s: s)
    t = lambda frame: int(frame) / fps + offset_s  # noqa: E731
    # Events on their frames, as the target counts them ("within 1 frame of 30 fps");
    # the durations in spatiotemporal.csv use the sub-frame times (events.csv's time_s).
    events = [(side(r["side"]), r["event"], t(r["frame"])) for r in rows(d / "events.csv")]
    bouts = [(t(r["first"]), t(r["last"])) for r in rows(d / "bouts.csv")]
    cycles, rejected = [], []
    for r in rows(d / "cycle_quality.csv"):
        c = (side(r["side"]), t(r["first_frame"]), t(r["last_frame"]))
        if r["accepted"] == "true":
            cycles.append(c)
        else:
            rejected.append(c + (r["reasons"],))
    curves = {}
    for r in rows(d / "cycles.csv"):
        curves.setdefault((side(r["side"]), r["joint"]), []).append(num(r["mean"]))
    params = {}
    for r in rows(d / "spatiotemporal.csv"):
        unit = r.get("unit", "")
        v = num(r["mean"])
        if unit in PIXEL_UNITS:
            v /= scale
        s = r["side"]
        if mirrored and s in OTHER:
            s = OTHER[s]
        if mirrored and r["parameter"].startswith("symmetry_index"):
            v = -v  # left vs right: exchanged sides flip the sign
        params[(r["parameter"], s)] = (v, unit)
    return Result(events, bouts, cycles, rejected, curves, params)


def inside(intervals, t, pad=0.0):
    return any(a - pad <= t <= b + pad for a, b in intervals)


def overlap(a, b):
    """Intersection of two lists of intervals."""
    out = []
    for x0, x1 in a:
        for y0, y1 in b:
            lo, hi = max(x0, y0), min(x1, y1)
            if lo <= hi:
                out.append((lo, hi))
    return out


def match(ref, var, key, tol):
    """Greedy nearest matching of items of equal `key` within `tol` seconds: pairs, unmatched."""
    pairs, used = [], set()
    cands = sorted(
        ((abs(r[2] - v[2]), i, j) for i, r in enumerate(ref) for j, v in enumerate(var)
         if key(r) == key(v) and abs(r[2] - v[2]) <= tol), key=lambda c: c[0])
    taken = set()
    for dt, i, j in cands:
        if i in taken or j in used:
            continue
        taken.add(i)
        used.add(j)
        pairs.append((ref[i], var[j]))
    return pairs, [r for i, r in enumerate(ref) if i not in taken], [v for j, v in enumerate(var) if j not in used]


def compare(ref, var, tol_s):
    """The figures of issue 37 for one variant against the original."""
    both = overlap(ref.bouts, var.bouts)
    key = lambda e: (e[0], e[1])  # noqa: E731
    # Events are matched anywhere (an event just outside a shifted bout edge still pairs), and
    # counted missing or extra only inside both results' bouts.
    pairs, missing, extra = match(ref.events, var.events, key, 2.0)
    near = [(r, v) for r, v in pairs if abs(r[2] - v[2]) <= tol_s + 1e-6]
    far = [(r, v) for r, v in pairs if abs(r[2] - v[2]) > tol_s + 1e-6]
    missing = [e for e in missing + [r for r, _ in far] if inside(both, e[2])]
    extra = [e for e in extra + [v for _, v in far] if inside(both, e[2])]
    errs = [abs(r[2] - v[2]) for r, v in pairs if inside(both, r[2])]
    cyc_key = lambda c: c[0]  # noqa: E731
    cpairs, cmiss, cextra = match(
        [(c[0], c[2], c[1]) for c in ref.cycles], [(c[0], c[2], c[1]) for c in var.cycles],
        cyc_key, tol_s + 1e-6)
    cpairs = [(a, b) for a, b in cpairs if abs(a[1] - b[1]) <= tol_s + 1e-6]
    rms = {}
    for k, a in ref.curves.items():
        b = var.curves.get(k)
        if b and len(a) == len(b):
            d = [(x - y) ** 2 for x, y in zip(a, b) if math.isfinite(x) and math.isfinite(y)]
            if d:
                rms[f"{k[0]}_{k[1]}"] = math.sqrt(sum(d) / len(d))
    params = {}
    for k, (a, unit) in ref.params.items():
        b = var.params.get(k, (math.nan, unit))[0]
        if not (math.isfinite(a) and math.isfinite(b)):
            continue
        if k[0].startswith("symmetry_index"):
            params[f"{k[0]}_{k[1]}"] = {"ref": a, "var": b, "abs": abs(a - b)}
        elif abs(a) > 0:
            params[f"{k[0]}_{k[1]}"] = {"ref": a, "var": b, "rel": abs(a - b) / abs(a)}
    bout_edges = [
        max(abs(a[0] - b[0]), abs(a[1] - b[1])) for a, b in zip(ref.bouts, var.bouts)
    ] if len(ref.bouts) == len(var.bouts) else None
    return {
        "events_ref": len([e for e in ref.events if inside(both, e[2])]),
        "events_var": len([e for e in var.events if inside(both, e[2])]),
        "events_within_tol": len([p for p in near if inside(both, p[0][2])]),
        "max_event_error_s": max(errs) if errs else None,
        "missing_events": [list(e) for e in missing],
        "extra_events": [list(e) for e in extra],
        "bouts_ref": ref.bouts,
        "bouts_var": var.bouts,
        "bout_edge_max_s": max(bout_edges) if bout_edges else None,
        "cycles_ref": len(ref.cycles),
        "cycles_var": len(var.cycles),
        "cycles_same": len(cmiss) == 0 and len(cextra) == 0 and len(cpairs) == len(ref.cycles),
        "cycles_missing": [list(c) for c in cmiss],
        "cycles_extra": [list(c) for c in cextra],
        "rejected_var": [list(c) for c in var.rejected],
        "curve_rms_deg": rms,
        "params": params,
    }


def verdict(c, max_rms=2.0, max_rel=0.02, max_si=2.0):
    """The issue's targets for one comparison, in two groups of what failed (empty: all met):
    `decisions` (events within the tolerance, none missing or extra in the bouts, the same
    accepted cycles) and `precision` (mean curves, spatiotemporal parameters)."""
    decisions, precision = [], []
    if c["missing_events"] or c["extra_events"]:
        decisions.append(f"events: {len(c['missing_events'])} missing, {len(c['extra_events'])} extra or moved")
    if not c["cycles_same"]:
        decisions.append(f"cycles: {c['cycles_var']} accepted vs {c['cycles_ref']}")
    bad = {k: round(v, 2) for k, v in c["curve_rms_deg"].items() if v > max_rms}
    if bad:
        precision.append(f"curves RMS > {max_rms} deg: {bad}")
    badp = {k: round(v["rel"] * 100, 1) for k, v in c["params"].items() if "rel" in v and v["rel"] > max_rel}
    bads = {k: round(v["abs"], 1) for k, v in c["params"].items() if "abs" in v and v["abs"] > max_si}
    if badp:
        precision.append(f"parameters off by > {max_rel * 100:.0f} %: {badp}")
    if bads:
        precision.append(f"symmetry indices off by > {max_si} points: {bads}")
    return {"decisions": decisions, "precision": precision}


def failed(v):
    return v["decisions"] + v["precision"]
