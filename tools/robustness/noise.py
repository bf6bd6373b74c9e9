"""Keypoint noise for the matrix (issue 37): a run's keypoints.csv with Gaussian noise of a given
size added to every present x and y, for `gait kin` to analyse again."""
import csv
import random


def jitter(src, dst, sigma_px, seed):
    """Copies a DeepLabCut CSV, adding N(0, sigma_px) to each present coordinate."""
    rng = random.Random(seed)
    with open(src, newline="") as f:
        table = list(csv.reader(f))
    coords = table[2]
    for row in table[3:]:
        for c in range(1, len(row)):
            if coords[c] in ("x", "y") and row[c] != "":
                row[c] = f"{float(row[c]) + rng.gauss(0.0, sigma_px):.3f}"
    with open(dst, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(table)
