"""Issue 40: gait's README command against myogait 0.9.2's full pipeline.

Run through tools/bench/main_job.sh, which sets up both tools. Each measured
command is a child process; wait4 gives its CPU time (user + sys, its
waited-for descendants included: ffmpeg, chromium) and its peak RSS (the
largest single process of that tree, not their sum). Rounds are interleaved,
in a rotating order, so a machine that slows down over the run (other work,
heat) weighs on every command alike.

The same file is also the myogait child (--myogait-child, under myogait's venv
python), so the measured myogait process does only myogait's work.
"""
import argparse
import csv
import datetime
import hashlib
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LEAN = ["--set", "report.overlay=false", "--set", "report.pdf=false"]
NAMES = ["gait-full", "gait-lean", "myogait"]


def myogait_child(video, out):
    """myogait's run_pipeline with mediapipe, then its exports and PDF report."""
    import myogait.models.mediapipe as mp_backend

    # myogait tries mediapipe's Tasks API first, which downloads
    # pose_landmarker_heavy.task on first use (no option turns that off). Make
    # that step fail at once, as it would offline, so myogait takes its own
    # fallback: the legacy mp.solutions.pose (model_complexity=1, the
    # pose_landmark_full model that the mediapipe wheel bundles).
    def no_download(model_path=None):
        raise RuntimeError("benchmark runs offline: legacy pose API")

    mp_backend._ensure_model = no_download
    import myogait
    from myogait import export, report

    r = myogait.run_pipeline(video, model="mediapipe", show_progress=False)
    data, cycles, stats = r["data"], r["cycles"], r["stats"] or {}
    o = Path(out)
    export.export_json(data, str(o / "result.json"), cycles, stats)
    export.export_summary_json(data, cycles, stats, str(o / "summary.json"))
    export.export_csv(data, str(o), cycles, stats)
    export.export_mot(data, str(o / "kinematics.mot"))
    export.export_trc(data, str(o / "markers.trc"))
    export.export_c3d(data, str(o / "markers.c3d"))
    export.export_excel(data, str(o / "gait_analysis.xlsx"), cycles, stats)
    report.generate_report(data, cycles, stats, str(o / "report.pdf"), language="en")


def measure(argv, log):
    """Wall time, CPU time and peak RSS of one child process."""
    with open(log, "w") as f:
        t0 = time.perf_counter()
        child = subprocess.Popen(argv, stdout=f, stderr=subprocess.STDOUT, cwd=ROOT)
        _, status, ru = os.wait4(child.pid, 0)
        wall = time.perf_counter() - t0
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        sys.exit(f"bench: {argv[0]} exited {child.returncode}; see {log}")
    return {"wall_s": round(wall, 3), "cpu_s": round(ru.ru_utime + ru.ru_stime, 3),
            "user_s": round(ru.ru_utime, 3), "sys_s": round(ru.ru_stime, 3),
            "peak_rss_mib": round(ru.ru_maxrss / 1024, 1)}  # Linux: KiB


def commands(args, runs):
    """The three measured commands, each with its own output folder."""
    gait, video = str(args.gait), str(args.input)
    out = {n: runs / n for n in NAMES}
    return {
        "gait-full": [gait, "run", "--input", video, "--out", str(out["gait-full"])],
        "gait-lean": [gait, "run", "--input", video, "--out", str(out["gait-lean"])] + LEAN,
        "myogait": [args.myogait_python, str(Path(__file__).resolve()), "--myogait-child",
                    video, str(out["myogait"])],
    }, out


def run_rounds(args, runs):
    """args.rounds interleaved rounds; round r starts r places further on."""
    cmds, outs = commands(args, runs)
    rows = []
    for r in range(args.rounds):
        for name in NAMES[r % 3:] + NAMES[:r % 3]:
            # A fresh folder: gait's only cache is OUT/cache (run.cache_dir
            # unset), so nothing is reused between rounds.
            shutil.rmtree(outs[name], ignore_errors=True)
            outs[name].mkdir(parents=True)
            m = measure(cmds[name], runs / f"{name}.log")
            if name.startswith("gait"):
                m["frames_from_cache"] = read_json(outs[name] / "run.json")["frames_from_cache"]
                if m["frames_from_cache"]:
                    sys.exit(f"bench: {name} took frames from a cache; timings not comparable")
            rows.append({"round": r + 1, "command": name, **m})
            print(f"round {r + 1} {name}: {m}", flush=True)
    return cmds, outs, rows


def shown(path):
    """A path as the README writes it: relative to the repository root."""
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def read_json(path):
    with open(path) as f:
        return json.load(f)


def machine():
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((l.split(":", 1)[1].strip() for l in lscpu.splitlines()
                  if l.startswith("Model name:")), "?")
    return {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "cpu_model": model, "cores": os.cpu_count(),
            # Other work on the machine shows in wall time first; say how much there was.
            "load_1min_start": os.getloadavg()[0]}


def versions(args):
    gait = subprocess.run([str(args.gait), "--version"], capture_output=True, text=True)
    py = ("import importlib.metadata as m; "
          "print(m.version('myogait'), m.version('mediapipe'))")
    myo = subprocess.run([args.myogait_python, "-c", py], capture_output=True, text=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True)
    m, mp = (myo.stdout.split() + ["?", "?"])[:2]
    return {"gait": gait.stdout.strip(), "checkout": commit.stdout.strip(),
            "gait_sha256": sha256(args.gait),
            "myogait": m, "mediapipe": mp}


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def gait_subject(run_json):
    """Whom gait followed and what it found, from its run.json."""
    sub = run_json["subject"]
    kin = run_json.get("extra", {}).get("kinematics", {})
    return {"pose_model": run_json.get("stages", {}).get("pose", {}).get("kind"),
            "track": sub["chosen"], "in_view": sub.get("in_view"), "reason": sub.get("reason"),
            "events": len(kin.get("events", [])), "cycles_accepted": kin.get("cycles_accepted")}


def gait_hips(keypoints_csv):
    """gait's mid-hip per frame (x, y px) from its DeepLabCut-style CSV."""
    with open(keypoints_csv) as f:
        rows = list(csv.reader(f))
    col = rows[1].index("mid_hip")  # bodyparts row; x, y, likelihood follow
    return {int(r[0]): (float(r[col]), float(r[col + 1])) for r in rows[3:] if r[col]}


def myogait_hips(result):
    """myogait's mid-hip per frame in image pixels, from its result JSON."""
    w, h = result["meta"]["width"], result["meta"]["height"]
    flip = result["extraction"].get("was_flipped", False)  # x mirrored when walking right
    hips = {}
    for f in result.get("frames_raw") or result["frames"]:
        lm = f.get("landmarks") or {}
        if lm.get("LEFT_HIP") and lm.get("RIGHT_HIP"):
            x = (lm["LEFT_HIP"]["x"] + lm["RIGHT_HIP"]["x"]) / 2
            hips[f["frame_idx"]] = ((1 - x if flip else x) * w,
                                    (lm["LEFT_HIP"]["y"] + lm["RIGHT_HIP"]["y"]) / 2 * h)
    return hips


def myogait_subject(result, gait_run, gait_csv):
    """Whom myogait followed and what it found.

    myogait keeps one person per frame and no identity, so the person is told
    by position: in how many of the frames where gait has its subject's hips
    myogait's mid-hip is within a tenth of the frame width of them.
    """
    mine, theirs = myogait_hips(result), gait_hips(gait_csv)
    both = sorted(set(mine) & set(theirs))
    near = [i for i in both if math.dist(mine[i], theirs[i]) < result["meta"]["width"] / 10]
    mx = statistics.median(p[0] for p in mine.values())
    my = statistics.median(p[1] for p in mine.values())
    track = min(gait_run["subject"]["tracks"], key=lambda t: math.dist(t["mean_centre"], (mx, my)))
    ev = result.get("events", {})
    kept = result.get("cycles", {}).get("cycles", [])
    return {"frames_with_hips": len(mine), "first_last_frame": [min(mine), max(mine)],
            "median_mid_hip_px": [round(mx), round(my)], "gait_track_nearest_median": track["id"],
            "frames_gait_has_subject": len(both), "frames_on_gait_subject": len(near),
            "frames_on_gait_subject_range": [near[0], near[-1]] if near else None,
            "events": {k: len(ev.get(k, [])) for k in ("left_hs", "right_hs", "left_to", "right_to")},
            "cycles_kept": {s: sum(c["side"] == s for c in kept) for s in ("left", "right")},
            "cycles_segmented": len(result.get("cycles_data", {}).get("cycles", [])),
            "cycles_kept_frames": [[c["start_frame"], c["end_frame"]] for c in kept]}


def subjects(outs):
    run = read_json(outs["gait-full"] / "run.json")
    result = read_json(outs["myogait"] / "result.json")
    return {"gait": gait_subject(run),
            "myogait": myogait_subject(result, run, outs["gait-full"] / "keypoints.csv")}


def header(info):
    v, mc = info["versions"], info["machine"]
    return [f"Date {mc['date']}; CPU {mc['cpu_model']}, {mc['cores']} cores (1-min load average "
            f"{mc['load_1min_start']:.1f} at the start, {mc['load_1min_end']:.1f} at the end); "
            f"{info['rounds']} round(s), interleaved; input `{info['input']}`.",
            f"{v['gait']} (`{info['gait_binary']}`, sha256 {v['gait_sha256'][:12]}, checkout "
            f"{v['checkout']}; pose model {info['subjects']['gait']['pose_model']}); "
            f"myogait {v['myogait']}, mediapipe {v['mediapipe']} (legacy pose API).", ""]


def table(rows, info):
    """The Markdown report: medians, each round, ratios of the medians."""
    per = {n: [r for r in rows if r["command"] == n] for n in NAMES}
    med = {n: {k: statistics.median(r[k] for r in per[n]) for k in ("wall_s", "cpu_s", "peak_rss_mib")}
           for n in NAMES}
    each = lambda n, k, d=1: ", ".join(f"{r[k]:.{d}f}" for r in sorted(per[n], key=lambda r: r["round"]))
    lines = header(info) + [
        "| command | wall s (median) | wall s (rounds) | CPU s (median) | CPU s (rounds) "
        "| peak RSS MiB (median) | peak RSS MiB (rounds) |",
        "| --- | ---: | --- | ---: | --- | ---: | --- |"]
    for n in NAMES:
        m = med[n]
        lines.append(f"| {LABELS[n]} | {m['wall_s']:.1f} | {each(n, 'wall_s')} | {m['cpu_s']:.1f} | "
                     f"{each(n, 'cpu_s')} | {m['peak_rss_mib']:.0f} | {each(n, 'peak_rss_mib', 0)} |")
    lines += ["", "| ratio of the medians | wall | CPU |", "| --- | ---: | ---: |"]
    for n in NAMES[:2]:
        lines.append(f"| {n} / myogait | {med[n]['wall_s'] / med['myogait']['wall_s']:.2f} | "
                     f"{med[n]['cpu_s'] / med['myogait']['cpu_s']:.2f} |")
    return "\n".join(lines + ["", who(info["subjects"])]) + "\n", med


LABELS = {"gait-full": "gait-full: `gait run --input VIDEO --out DIR` (README)",
          "gait-lean": "gait-lean: the same with `--set report.overlay=false --set report.pdf=false`",
          "myogait": "myogait: `run_pipeline(model=\"mediapipe\")`, its exports and PDF report"}


def who(s):
    """One paragraph: did both tools analyse the same person?"""
    g, m = s["gait"], s["myogait"]
    return (f"What each analysed: gait followed track {g['track']}, frames {g['in_view']} ({g['reason']}): "
            f"{g['events']} events, cycles accepted {g['cycles_accepted']}. myogait (one person a frame, "
            f"no tracking) had hips in {m['frames_with_hips']} frames ({m['first_last_frame'][0]}-"
            f"{m['first_last_frame'][1]}), median mid-hip {m['median_mid_hip_px']} px, nearest gait's "
            f"track {m['gait_track_nearest_median']}; on gait's subject in {m['frames_on_gait_subject']} "
            f"of the {m['frames_gait_has_subject']} frames where gait has it "
            f"(frames {m['frames_on_gait_subject_range']}); events {m['events']}, cycles kept "
            f"{m['cycles_kept']} of {m['cycles_segmented']} segmented, frames {m['cycles_kept_frames']}.")


def parse():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--gait", type=Path, default=Path("target/debug/gait"))
    p.add_argument("--input", type=Path, default=Path("data/sample/sports2d-demo.mp4"))
    p.add_argument("--md", type=Path, help="write the Markdown table here too")
    p.add_argument("--json", type=Path, help="write every measurement here")
    p.add_argument("--runs", type=Path, default=Path("target/bench/runs"),
                   help="output folders and logs of the measured commands")
    p.add_argument("--myogait-python", required=True, help="set by main_job.sh")
    a = p.parse_args()
    if a.rounds < 1:
        p.error("--rounds must be at least 1")
    # Paths are relative to the repository root, as in the README.
    a.gait, a.input, a.runs = (x if x.is_absolute() else ROOT / x for x in (a.gait, a.input, a.runs))
    if not os.access(a.gait, os.X_OK):
        sys.exit(f"bench: no gait binary at {a.gait}: cargo build -p gait-cli, or pass --gait")
    return a


def main():
    if sys.argv[1:2] == ["--myogait-child"]:
        return myogait_child(*sys.argv[2:4])
    args = parse()
    info = {"machine": machine(), "versions": versions(args), "rounds": args.rounds,
            "input": shown(args.input), "gait_binary": shown(args.gait)}
    print(f"bench: {info['machine']}", flush=True)
    cmds, outs, rows = run_rounds(args, args.runs)
    # Another build may replace the binary mid-run; then rounds would mix two.
    if sha256(args.gait) != info["versions"]["gait_sha256"]:
        sys.exit(f"bench: {args.gait} changed during the benchmark; run it again")
    info["machine"]["load_1min_end"] = os.getloadavg()[0]
    info["subjects"] = subjects(outs)
    md, med = table(rows, info)
    print("\n" + md)
    if args.md:
        args.md.write_text(md)
    if args.json:
        info.update(commands=cmds, runs=rows, medians=med)
        args.json.write_text(json.dumps(info, indent=2) + "\n")


if __name__ == "__main__":
    main()
