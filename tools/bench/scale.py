"""Cost as the work grows (issue 40): the README's main command on the sample, on the same walk at
1080p and 4K, and on a 2-minute recording (the sample concatenated), each in a fresh folder, interleaved
over rounds: seconds per video second and peak RSS, each against the sample's of the same round.

    python3 tools/bench/scale.py [--gait target/debug/gait] [--rounds 1] [--md OUT.md]

Videos are made once with ffmpeg under target/bench/scale/ (the 1080p and 4K copies upscaled as the
robustness matrix's 4K variant: H.264 CRF 18).
"""
import argparse
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "data/sample/sports2d-demo.mp4"
sys.path.insert(0, str(ROOT / "tools/robustness"))
from variants import probe  # noqa: E402  (width, height, fps, frames) by ffprobe


def make_videos(work):
    """The sample, its 1080p and 4K copies and a 2-minute concatenation (16 copies), made once."""
    work.mkdir(parents=True, exist_ok=True)
    for name, height in [("1080p", 1080), ("4k", 2160)]:
        copy = work / f"{name}.mp4"
        if not copy.exists():
            subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", str(SAMPLE), "-an", "-vf", f"scale=-2:{height}",
                            "-c:v", "libx264", "-pix_fmt", "yuv420p", "-preset", "veryfast", "-crf", "18",
                            str(copy)], check=True)
    long = work / "2min.mp4"
    if not long.exists():
        listing = work / "concat.txt"
        listing.write_text("".join(f"file '{SAMPLE}'\n" for _ in range(16)))
        # Stream copy: the same frames 16 times, no re-encode.
        subprocess.run(["ffmpeg", "-v", "error", "-y", "-f", "concat", "-safe", "0", "-i", str(listing),
                        "-c", "copy", "-an", str(long)], check=True)
    return {"sample": SAMPLE, "1080p": work / "1080p.mp4", "4k": work / "4k.mp4", "2min": long}


def measure(gait, video, out):
    """Wall seconds, CPU seconds and peak RSS (MiB) of `gait run` into a fresh `out`."""
    shutil.rmtree(out, ignore_errors=True)
    t = time.monotonic()
    proc = subprocess.Popen([str(gait), "run", "--input", str(video), "--out", str(out), "--no-progress"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - t
    err = proc.stderr.read().decode(errors="replace")
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"gait run on {video} failed: {err.strip().splitlines()[-1:]}")
    # ru_maxrss of the largest child: gait itself (ffmpeg and Chromium are smaller).
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait", default=str(ROOT / "target/debug/gait"))
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--md")
    a = ap.parse_args()
    work = ROOT / "target/bench/scale"
    videos = make_videos(work)
    seconds = {k: probe(v)[3] / probe(v)[2] for k, v in videos.items()}
    rows = {k: [] for k in videos}
    for r in range(a.rounds):
        for name, video in videos.items():
            rows[name].append(measure(a.gait, video, work / f"run-{name}"))
            w, c, m = rows[name][-1]
            print(f"round {r + 1} {name}: {w:.1f} s wall, {c:.1f} s CPU, {m:.0f} MiB", flush=True)
    base = statistics.median(w for w, _, _ in rows["sample"]) / seconds["sample"]
    base_rss = statistics.median(m for _, _, m in rows["sample"])
    lines = ["| video | video seconds | wall (s, median) | s per video second | vs the sample | peak RSS (MiB) | vs the sample |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for name in videos:
        w = statistics.median(x[0] for x in rows[name])
        m = statistics.median(x[2] for x in rows[name])
        per = w / seconds[name]
        lines.append(f"| {name} | {seconds[name]:.1f} | {w:.1f} | {per:.2f} | {per / base:.2f} | {m:.0f} | {m / base_rss:.2f} |")
    table = "\n".join(lines)
    print(table)
    if a.md:
        pathlib.Path(a.md).write_text(table + "\n")


if __name__ == "__main__":
    main()
