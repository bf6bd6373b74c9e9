#!/usr/bin/env python3
"""Compare the keypoints and gait events of two gait runs (or two DeepLabCut keypoints CSVs).

    python3 tools/python/compare_runs.py RUN_A RUN_B [--frames FIRST-LAST] [--per-frame [PX]]

RUN_A / RUN_B: a run folder (its keypoints.csv and events.csv) or a keypoints CSV (DeepLabCut layout, three
header rows; events.csv next to it is used when there is one). Prints, per lower-limb keypoint (left/right hip,
knee, ankle, heel, toe), the number of frames where both runs found it and the median and largest distance in
pixels between them; the median over all those keypoints and frames; and how the events of A match those of
B (same side and event, at most 1 frame apart, each event of B used once). --frames limits the keypoint
comparison to a range of input frames (inclusive); --per-frame lists every frame whose lower-limb median
distance is above PX (default 1), with the frames where only one run found a pose. Standard library only;
exits 0 whatever the numbers (2 on an unreadable input).
"""

import argparse
import csv
import math
import os
import statistics
import sys

LOWER_LIMB = [
    f"{side}_{joint}" for joint in ("hip", "knee", "ankle", "heel", "toe") for side in ("left", "right")
]
EVENT_TOLERANCE = 1


def fail(message):
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def paths(arg):
    """(keypoints CSV, events CSV or None) of a run folder or a keypoints CSV."""
    if os.path.isdir(arg):
        kp, ev = os.path.join(arg, "keypoints.csv"), os.path.join(arg, "events.csv")
    else:
        kp, ev = arg, os.path.join(os.path.dirname(arg) or ".", "events.csv")
    if not os.path.isfile(kp):
        fail(f"{kp}: no such file")
    return kp, ev if os.path.isfile(ev) else None


def read_keypoints(path):
    """{frame: {name: (x, y)}} with only the keypoints found (x and y given, likelihood > 0)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if len(rows) < 3 or [r[0] for r in rows[:3]] != ["scorer", "bodyparts", "coords"]:
        fail(f"{path}: not a DeepLabCut keypoints CSV (scorer/bodyparts/coords header rows)")
    parts, coords = rows[1], rows[2]
    columns = {}
    for i in range(1, len(parts)):
        columns.setdefault(parts[i], {})[coords[i]] = i
    missing = [n for n in LOWER_LIMB if not {"x", "y"} <= set(columns.get(n, {}))]
    if missing:
        fail(f"{path}: no columns for {', '.join(missing)}")
    out = {}
    for row in rows[3:]:
        if not row:
            continue
        found = {}
        for name in LOWER_LIMB:
            c = columns[name]
            x, y = row[c["x"]], row[c["y"]]
            lik = row[c["likelihood"]] if "likelihood" in c else "1"
            if x and y and not (lik and float(lik) <= 0.0):
                found[name] = (float(x), float(y))
        out[int(float(row[0]))] = found
    return out


def read_events(path):
    if path is None:
        return None
    with open(path, newline="") as fh:
        return [(r["side"], r["event"], int(r["frame"])) for r in csv.DictReader(fh)]


def match_events(a, b):
    """(matched pairs (event of A, frame in B), unmatched of A, unmatched of B)."""
    free = list(b)
    matched, lone = [], []
    for side, event, frame in sorted(a, key=lambda e: e[2]):
        near = [e for e in free if e[0] == side and e[1] == event and abs(e[2] - frame) <= EVENT_TOLERANCE]
        if near:
            best = min(near, key=lambda e: abs(e[2] - frame))
            free.remove(best)
            matched.append(((side, event, frame), best[2]))
        else:
            lone.append((side, event, frame))
    return matched, lone, free


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_a")
    ap.add_argument("run_b")
    ap.add_argument("--frames", help="FIRST-LAST: compare keypoints in these input frames only")
    ap.add_argument("--per-frame", nargs="?", const=1.0, type=float, metavar="PX",
                    help="list frames whose lower-limb median distance exceeds PX (default 1)")
    args = ap.parse_args()
    (kp_a, ev_a), (kp_b, ev_b) = paths(args.run_a), paths(args.run_b)
    a, b = read_keypoints(kp_a), read_keypoints(kp_b)
    frames = sorted(set(a) | set(b))
    if args.frames:
        first, last = (int(v) for v in args.frames.split("-"))
        frames = [f for f in frames if first <= f <= last]

    print(f"A: {kp_a}\nB: {kp_b}")
    posed_a = sum(1 for f in frames if a.get(f))
    posed_b = sum(1 for f in frames if b.get(f))
    both = [f for f in frames if a.get(f) and b.get(f)]
    print(f"frames: {len(frames)}; with lower-limb keypoints: A {posed_a}, B {posed_b}, both {len(both)}")

    dist = {name: [] for name in LOWER_LIMB}
    per_frame = {}
    for f in frames:
        ka, kb = a.get(f, {}), b.get(f, {})
        ds = []
        for name in LOWER_LIMB:
            if name in ka and name in kb:
                d = math.dist(ka[name], kb[name])
                dist[name].append(d)
                ds.append(d)
        if ds:
            per_frame[f] = ds

    print(f"\n{'keypoint':<12} {'frames':>6} {'median px':>10} {'max px':>10}")
    for name in LOWER_LIMB:
        d = dist[name]
        if d:
            print(f"{name:<12} {len(d):>6} {statistics.median(d):>10.3f} {max(d):>10.3f}")
        else:
            print(f"{name:<12} {0:>6} {'-':>10} {'-':>10}")
    pooled = [d for ds in dist.values() for d in ds]
    if pooled:
        print(f"{'lower limb':<12} {len(pooled):>6} {statistics.median(pooled):>10.3f} {max(pooled):>10.3f}"
              "  (all keypoints and frames)")

    if args.per_frame is not None:
        big = [(f, statistics.median(ds), max(ds)) for f, ds in sorted(per_frame.items())
               if statistics.median(ds) > args.per_frame]
        print(f"\nframes with a lower-limb median above {args.per_frame:g} px: {len(big)} of {len(per_frame)}")
        for f, med, mx in big:
            print(f"  frame {f:>5}: median {med:9.2f}  max {mx:9.2f}")
        only_a = [f for f in frames if a.get(f) and not b.get(f)]
        only_b = [f for f in frames if b.get(f) and not a.get(f)]
        print(f"pose in A only: {ranges(only_a)}\npose in B only: {ranges(only_b)}")

    events_a, events_b = read_events(ev_a), read_events(ev_b)
    if events_a is None or events_b is None:
        which = " and ".join(n for n, e in (("A", events_a), ("B", events_b)) if e is None)
        print(f"\nevents: no events.csv for {which}")
        return
    matched, lone_a, lone_b = match_events(events_a, events_b)
    print(f"\nevents (same side and event, within {EVENT_TOLERANCE} frame): A {len(events_a)}, B {len(events_b)}, "
          f"matched {len(matched)}, unmatched in A {len(lone_a)}, unmatched in B {len(lone_b)}")
    shifted = [(e, fb) for e, fb in matched if fb != e[2]]
    for (side, event, fa), fb in shifted:
        print(f"  {side} {event}: A frame {fa}, B frame {fb}")
    for side, event, f in lone_a:
        print(f"  only A: {side} {event} frame {f}")
    for side, event, f in lone_b:
        print(f"  only B: {side} {event} frame {f}")


def ranges(frames):
    """'3-7, 9' for [3, 4, 5, 6, 7, 9]; 'none' when empty."""
    out, start = [], None
    for i, f in enumerate(frames):
        if start is None:
            start = f
        if i + 1 == len(frames) or frames[i + 1] != f + 1:
            out.append(f"{start}" if start == f else f"{start}-{f}")
            start = None
    return ", ".join(out) or "none"


if __name__ == "__main__":
    main()
