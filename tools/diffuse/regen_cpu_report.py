#!/usr/bin/env python3
"""The markdown table of tools/diffuse/bench_regen_cpu.sh from its JSON lines.

Usage: regen_cpu_report.py RESULTS.jsonl [SAMPLE_RUN_JSON]

Each line of a timed process (bench_diffusers.py `diffusers` or regen_bench, with "setting" added
by the script) has per_frame_s, every timed frame in order. A setting with "init": "previous" (the
cpu setting) starts its first frame from noise and every later one from the frame before, so its
s/frame is the median of the later frames over all rounds, and its first frame is given apart
(first_s; per_frame_s[0] where a line lacks it).

The whole-video estimate multiplies each setting's median seconds per frame by the frames a
[selection] mode = "poor" run of the sample regenerated; SAMPLE_RUN_JSON is such a run's run.json.
Without it, the counts measured in BENCHMARKS.md's selection table (88 of 230 frames) are used,
and the table says so. For an init = "previous" setting, each run of consecutive regenerated
frames (a range of run.json's selection.regenerated: the regenerator starts it from noise) costs
its first frame's time once, the others the median: regenerated x median + runs x (first -
median). The first frame also carries the process's one-time warm-up (the script times no
warm-up call), so this leans high. Without SAMPLE_RUN_JSON the number of runs is unknown, and the
estimate is the range from 1 run to one run per frame.

Issue 30's targets, from the same run: our cpu / fast per-frame median <= 0.1, our cpu per-frame
median <= 20 s, ours / diffusers at cpu <= 0.8.
"""

import json
import statistics
import sys

ORDER = {"paper": 0, "fast": 1, "cpu": 2}
IMPL_ORDER = {"diffusers": 0, "gait": 1}


def describe(r):
    """The settings of a result line, in words."""
    steps = r["steps"]
    d = (f"{steps} {r.get('scheduler', 'unipc')} steps, CFG to {r.get('guidance_end', 1.0)}, "
         f"ControlNet {r.get('control_guidance', [0.0, 1.0])}")
    if int(r.get("cache_interval", 1)) > 1:
        d += f", DeepCache every {r['cache_interval']} (branch {r.get('cache_branch', 0)})"
    if float(r.get("token_merge_ratio", 0.0)) > 0:
        d += f", ToMe {r['token_merge_ratio']}"
    width, height = r.get("width") or r["size"], r["size"]
    d += f", {width}x{height}"
    if r.get("init") == "previous":
        strength = float(r["strength"])
        d += f", from the previous frame at strength {strength} ({int(steps * strength)} steps)"
    return d


def collect(runs):
    """Per (setting, impl): the steady per-frame seconds, the first frames (init = "previous"
    only) and the setting's keys. Both sides of a setting get the same keys from the script, so
    a setting is init = "previous" when any of its lines says so, and its description merges its
    lines (diffusers' keys first: bench_diffusers.py echoes all of them)."""
    previous = {r["setting"] for r in runs if r.get("init") == "previous"}
    keys = {}
    for r in sorted(runs, key=lambda r: r["impl"] == "diffusers"):
        keys.setdefault(r["setting"], {}).update(r)
    groups = {}
    for r in runs:
        g = groups.setdefault((r["setting"], r["impl"]), dict(steady=[], first=[], row=keys[r["setting"]]))
        per_frame = r.get("per_frame_s") or [r["median_s"]]
        if r["setting"] in previous:
            g["first"].append(r.get("first_s", per_frame[0]))
            g["steady"].extend(per_frame[1:] or [r["median_s"]])
        else:
            g["steady"].extend(per_frame)
    return {k: dict(g, median=statistics.median(g["steady"]),
                    first=statistics.median(g["first"]) if g["first"] else None)
            for k, g in groups.items()}


def minutes(frames, median, first, runs):
    """Minutes for `frames` regenerated frames in `runs` runs (first: the first frame of a run,
    None when every frame costs the median)."""
    if first is None:
        return frames * median / 60
    return (frames * median + runs * (first - median)) / 60


def num(x):
    """Seconds or minutes, to 3 significant digits (205, 14.2, 0.0536)."""
    return f"{x:.3g}" if x < 1000 else f"{x:.0f}"


def main():
    rows = [json.loads(line) for line in open(sys.argv[1]) if line.startswith("{")]
    meta = next(r for r in rows if "cpu" in r)
    runs = [r for r in rows if "impl" in r]
    if not runs:
        raise SystemExit(f"{sys.argv[1]}: no benchmark results")
    bouts = None
    if len(sys.argv) > 2:
        sel = json.load(open(sys.argv[2]))["selection"]
        poor, total, source = sel["regenerated_count"], sel["frames"], sys.argv[2]
        bouts = len(sel["regenerated"])
    else:
        poor, total, source = 88, 230, "BENCHMARKS.md's selection table"
    groups = collect(runs)

    print(f"### Regeneration per frame on the CPU ({meta['date']}, {meta['cpu']}, flags: {meta['flags']}, "
          f"{meta['threads']} threads)\n")
    weights = ("Tiny random weights (the tests' configs, seed 0; the times mean nothing)" if meta.get("tiny")
               else "Random SD 1.5-size weights (seed 0)")
    print(f"{weights}, f32, guidance 7.5, the paper's prompts; median seconds per frame over "
          f"{meta['rounds']} interleaved round(s) (`tools/diffuse/bench_regen_cpu.sh`). A setting that "
          f"starts each frame from the previous one: s/frame is the median of the frames after the "
          f"first, which starts from noise (its own column).\n")
    print("| settings | implementation | s/frame | first frame, s | ours / diffusers | vs fast (same implementation) "
          "| vs paper (same implementation) | whole sample, poor frames only |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    key = lambda k: (ORDER.get(k[0], 9), k[0], IMPL_ORDER.get(k[1], 9), k[1])  # noqa: E731
    for setting, impl in sorted(groups, key=key):
        g = groups[(setting, impl)]
        s, first = g["median"], g["first"]
        ratio = lambda other: (f"{s / groups[other]['median']:.2f}"  # noqa: E731
                               if other in groups and other != (setting, impl) else "-")
        vs_diff = ratio((setting, "diffusers")) if impl == "gait" else "-"
        if first is None:
            whole = f"{num(minutes(poor, s, None, 0))} min"
        elif bouts is not None:
            whole = f"{num(minutes(poor, s, first, bouts))} min"
        else:
            whole = f"{num(minutes(poor, s, first, 1))}-{num(minutes(poor, s, first, poor))} min"
        first_txt = num(first) if first is not None else "-"
        print(f"| {setting}: {describe(g['row'])} | {impl} | {num(s)} | {first_txt} | {vs_diff} | "
              f"{ratio(('fast', impl))} | {ratio(('paper', impl))} | {whole} |")

    print(f"\nWhole sample: {poor} of its {total} frames regenerated (`[selection] mode = \"poor\"`, counts from "
          f"{source}); regenerating all {total} frames takes {total / poor:.1f}x as long.", end="")
    if any(g["first"] is not None for g in groups.values()):
        if bouts is not None:
            print(f" Starting from the previous frame: the {poor} frames come in {bouts} runs of consecutive "
                  f"frames, each run's first from noise (first-frame time, which includes the process's "
                  f"warm-up, so the estimate leans high), the others at s/frame.")
        else:
            print(" Starting from the previous frame: the number of runs of consecutive regenerated frames "
                  "(each starting from noise at the first-frame time) is unknown without a run.json, so "
                  "the range is from 1 run to one per frame.")
    else:
        print()

    ours_cpu, ours_fast, diff_cpu = groups.get(("cpu", "gait")), groups.get(("fast", "gait")), groups.get(
        ("cpu", "diffusers"))
    if ours_cpu or diff_cpu:
        print("\nIssue 30's targets (this run):\n")

        def line(what, value, fmt, target, ok):
            print(f"- {what}: {format(value, fmt)} (target <= {target}): {'met' if ok else 'NOT met'}")

        if ours_cpu and ours_fast:
            r = ours_cpu["median"] / ours_fast["median"]
            line("ours, cpu / fast per frame", r, ".3f", "0.1", r <= 0.1)
        if ours_cpu:
            line("ours, cpu s/frame (after the first)", ours_cpu["median"], ".3g", "20 s",
                 ours_cpu["median"] <= 20)
        if ours_cpu and diff_cpu:
            r = ours_cpu["median"] / diff_cpu["median"]
            line("ours / diffusers at cpu", r, ".2f", "0.8", r <= 0.8)
        if not ours_cpu:
            print("- ours: no results in this run (IMPLS=diffusers?)")


if __name__ == "__main__":
    main()
