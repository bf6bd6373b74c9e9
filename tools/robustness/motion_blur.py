#!/usr/bin/env python3
"""Long exposures and blended frames (issue 37, bad input): the original and copies filmed as with
a 1/30 s and a 1/60 s shutter (motion-interpolated to 120 fps, 4 or 2 frames averaged, back to 30
fps; the 1/30 s copy stored at CRF 12 and at CRF 23) and with each frame blended with the one
before (`tmix=frames=2`, a frame-rate conversion's ghosts), each run with the default pipeline and
with the motion-blur check off. Per stride: the foot's outline contrast swinging over standing
(cycle_quality.csv `swing_contrast`) and the verdict; per copy, with the check off, the mean
curves against the original's (RMS per side and joint, deg). Then the swing contrast of every
copy of the robustness matrix found under target/robustness (run matrix.py first).
BENCHMARKS.md, "Motion blur of a long exposure".

usage: motion_blur.py --gait target/debug/gait [--input VIDEO] [--work target/robustness/motion]
The 120 fps interpolation takes about 5 minutes a copy on one core; copies are kept in --work.
"""
import csv
import math
import pathlib
import subprocess
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from matrix import ROOT, copies_args, run  # noqa: E402

COPIES = {
    "shutter30_crf12": ("minterpolate=fps=120,tmix=frames=4,fps=30", "12"),
    "shutter30_crf23": ("minterpolate=fps=120,tmix=frames=4,fps=30", "23"),
    "shutter60_crf12": ("minterpolate=fps=120,tmix=frames=2,fps=30", "12"),
    "blended_crf12": ("tmix=frames=2", "12"),
}
OFF = ["--set", "kinematics.cycle_min_swing_contrast=0"]


def copy(original, name, folder):
    out = folder / f"{name}.mp4"
    if not out.exists():
        vf, crf = COPIES[name]
        subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", str(original), "-an", "-vf", vf,
                        "-c:v", "libx264", "-crf", crf, "-pix_fmt", "yuv420p", str(out)],
                       check=True)
    return out


def mean_curves(folder):
    """{(side, joint): [mean value per percent]} over the accepted cycles of cycles_all.csv."""
    sums = {}
    with open(folder / "cycles_all.csv") as f:
        for r in csv.DictReader(f):
            key = (r["side"], r["joint"], int(float(r["percent"])))
            sums.setdefault(key, []).append(float(r["value"]))
    out = {}
    for (side, joint, pct), v in sorted(sums.items()):
        out.setdefault((side, joint), []).append(sum(v) / len(v))
    return out


def rms_against(ref, folder):
    own = mean_curves(folder)
    out = {}
    for key, v in own.items():
        if key in ref and len(ref[key]) == len(v):
            out[key] = math.sqrt(sum((a - b) ** 2 for a, b in zip(ref[key], v)) / len(v))
    return out


def strides(folder):
    with open(folder / "cycle_quality.csv") as f:
        return list(csv.DictReader(f))


def report(name, folder, off, ref):
    print(f"{name}:")
    for r in strides(folder):
        verdict = "accepted" if r["accepted"] == "true" else "rejected: " + r["reasons"]
        print(f"  {r['side']:5} {r['first_frame']:>4}-{r['last_frame']:<4} "
              f"swing contrast {float(r['swing_contrast']):.2f}  {verdict}")
    rms = rms_against(ref, off)
    if rms:
        text = ", ".join(f"{s[0]} {j} {x:.1f}" for (s, j), x in sorted(rms.items()))
        print(f"  check off: mean curves RMS {text}; mean {sum(rms.values()) / len(rms):.2f},"
              f" worst {max(rms.values()):.2f}")


def matrix_copies():
    """The swing contrast per stride of every matrix copy found."""
    base = ROOT / "target/robustness"
    for q in sorted(base.glob("*/cycle_quality.csv")):
        values = [float(r["swing_contrast"]) for r in strides(q.parent)
                  if r.get("swing_contrast") not in (None, "")]
        if values:
            print(f"  matrix {q.parent.name:14} {min(values):.2f}-{max(values):.2f}")


def main():
    gait, work, original = copies_args(__doc__, "target/robustness/motion")
    run(gait, original, work / "original")
    ref = mean_curves(work / "original")
    report("original", work / "original", work / "original", ref)
    for name in COPIES:
        video = copy(original, name, work)
        run(gait, video, work / name)
        run(gait, video, work / f"{name}_off", OFF)
        report(name, work / name, work / f"{name}_off", ref)
    matrix_copies()


if __name__ == "__main__":
    main()
