#!/usr/bin/env python3
"""The pose model's jitter in a keypoints.csv (issue 38): per keypoint and per left/right pair,
the residual after a local quadratic fit over 9 frames (0.3 s at 30 fps: what a walk or a
jumping jack moves slower than), scaled to the noise it implies for white noise, in px and per
100 px of leg (hip-knee-ankle). Prints the correlation of the pair's residuals: the frontal
noise model of crates/gait-kin/tests/frontal_mocap.rs takes its numbers from this script.

    python3 tools/frontal/measure_jitter.py KEYPOINTS.csv FIRST LAST

Pure Python (no numpy) so it runs wherever tools/test.sh does."""
import csv
import math
import statistics
import sys

HALF = 4  # 9-frame window


def weights(half):
    """Central weights of a least-squares quadratic over -half..half (Savitzky-Golay)."""
    n = 2 * half + 1
    s2 = sum(t * t for t in range(-half, half + 1))
    s4 = sum(t ** 4 for t in range(-half, half + 1))
    det = n * s4 - s2 * s2
    return [(s4 - s2 * t * t) / det for t in range(-half, half + 1)]


def residuals(x, half=HALF):
    """x less its local quadratic fit, scaled to the white noise it implies."""
    w = weights(half)
    scale = math.sqrt(1 - w[half])
    return [
        (x[i] - sum(c * x[i - half + k] for k, c in enumerate(w))) / scale
        for i in range(half, len(x) - half)
    ]


def corr(a, b):
    ma, mb = statistics.fmean(a), statistics.fmean(b)
    num = sum((p - ma) * (q - mb) for p, q in zip(a, b))
    return num / math.sqrt(sum((p - ma) ** 2 for p in a) * sum((q - mb) ** 2 for q in b))


def main():
    path, first, last = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    rows = list(csv.reader(open(path)))
    names, coords, data = rows[1], rows[2], [r for r in rows[3:] if first <= int(r[0]) <= last]

    def col(name, c):
        i = next(k for k in range(len(names)) if names[k] == name and coords[k] == c)
        return [float(r[i]) for r in data]

    def dist(a, b, i):
        return math.hypot(col(a, "x")[i] - col(b, "x")[i], col(a, "y")[i] - col(b, "y")[i])

    legs = [dist("left_hip", "left_knee", i) + dist("left_knee", "left_ankle", i) for i in range(len(data))]
    leg = statistics.median(legs)
    print(f"{path} frames {first}-{last} ({len(data)}): leg {leg:.0f} px")
    for part in ["hip", "shoulder", "knee", "ankle"]:
        for c in "xy":
            a, b = residuals(col(f"left_{part}", c)), residuals(col(f"right_{part}", c))
            sa, sb = statistics.pstdev(a), statistics.pstdev(b)
            sd = statistics.pstdev([p - q for p, q in zip(a, b)])
            print(f"  {part:8s} {c}: left {sa:.2f} px, right {sb:.2f} px "
                  f"({(sa + sb) / 2 / leg * 100:.2f} per 100 px of leg), "
                  f"correlation {corr(a, b):+.2f}, left - right {sd:.2f} px ({sd / leg * 100:.2f} per 100 px)")


if __name__ == "__main__":
    main()
