#!/usr/bin/env python3
"""The walker out of focus (issue 37, bad input): the original and copies blurred by a Gaussian
of sigma 2, 4 and 8 px, each run with the default pipeline; per stride, the legs' blur as the run
measured it (cycle_quality.csv `blur_px`, over `leg_px`), the verdict, and each accepted
cycle's curves against the original's same cycle (RMS per joint, deg). BENCHMARKS.md,
"Blurred and slowed walks".

usage: blur.py --gait target/debug/gait [--input VIDEO] [--work target/robustness/blur]
"""
import csv
import math
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from matrix import copies_args, run  # noqa: E402

SIGMAS = [2, 4, 8]


def blurred(original, sigma, folder):
    out = folder / f"blur{sigma}.mp4"
    if not out.exists():
        subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", str(original), "-an", "-vf",
                        f"gblur=sigma={sigma}", "-c:v", "libx264", "-crf", "18", "-preset",
                        "veryfast", "-pix_fmt", "yuv420p", str(out)], check=True)
    return out


def curves(folder):
    """{(side, first, last): {joint: [value per percent]}} of cycles_all.csv."""
    out = {}
    with open(folder / "cycles_all.csv") as f:
        for r in csv.DictReader(f):
            key = (r["side"], int(r["first_frame"]), int(r["last_frame"]))
            out.setdefault(key, {}).setdefault(r["joint"], []).append(float(r["value"]))
    return out


def same_cycle(ref, key):
    """The original's cycle of the same side within 2 frames at both ends."""
    for k in ref:
        if k[0] == key[0] and abs(k[1] - key[1]) <= 2 and abs(k[2] - key[2]) <= 2:
            return k
    return None


def report(name, folder, ref):
    with open(folder / "cycle_quality.csv") as f:
        rows = list(csv.DictReader(f))
    own = curves(folder)
    print(f"{name}:")
    for r in rows:
        share = 100 * float(r["blur_px"]) / float(r["leg_px"])
        line = (f"  {r['side']:5} {r['first_frame']:>4}-{r['last_frame']:<4} blur {float(r['blur_px']):.2f} px"
                f" = {share:.2f} % of {float(r['leg_px']):.0f} px  "
                f"{'accepted' if r['accepted'] == 'true' else 'rejected: ' + r['reasons']}")
        key = (r["side"], int(r["first_frame"]), int(r["last_frame"]))
        match = same_cycle(ref, key)
        if key in own and match:
            rms = {j: math.sqrt(sum((a - b) ** 2 for a, b in zip(ref[match][j], v)) / len(v))
                   for j, v in sorted(own[key].items())}
            line += "  RMS " + ", ".join(f"{j} {x:.1f}" for j, x in rms.items())
        print(line)


def main():
    gait, work, original = copies_args(__doc__, "target/robustness/blur")
    run(gait, original, work / "original")
    ref = curves(work / "original")
    report("original", work / "original", ref)
    for sigma in SIGMAS:
        folder = work / f"sigma{sigma}"
        run(gait, blurred(original, sigma, work), folder)
        report(f"sigma {sigma} px", folder, ref)


if __name__ == "__main__":
    main()
