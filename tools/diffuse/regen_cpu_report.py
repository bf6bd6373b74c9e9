#!/usr/bin/env python3
"""The markdown table of tools/diffuse/bench_regen_cpu.sh from its JSON lines.

Usage: regen_cpu_report.py RESULTS.jsonl [SAMPLE_RUN_JSON]

The whole-video estimate multiplies each setting's median seconds per frame by the frames a
[selection] mode = "poor" run of the sample regenerated; SAMPLE_RUN_JSON is such a run's run.json.
Without it, the counts measured in BENCHMARKS.md's selection table (88 of 230 frames) are used,
and the table says so.
"""

import json
import statistics
import sys


def main():
    rows = [json.loads(line) for line in open(sys.argv[1]) if line.startswith("{")]
    meta = next(r for r in rows if "cpu" in r)
    runs = [r for r in rows if "impl" in r]
    if len(sys.argv) > 2:
        sel = json.load(open(sys.argv[2]))["selection"]
        poor, total, source = sel["regenerated_count"], sel["frames"], sys.argv[2]
    else:
        poor, total, source = 88, 230, "BENCHMARKS.md's selection table"
    med = {}
    for r in runs:
        med.setdefault((r["setting"], r["impl"]), []).extend(r["per_frame_s"])
    med = {k: statistics.median(v) for k, v in med.items()}
    print(f"### Regeneration per frame on the CPU ({meta['date']}, {meta['cpu']}, flags: {meta['flags']}, "
          f"{meta['threads']} threads)\n")
    print(f"Random SD 1.5-size weights (seed 0), 512x512, f32, guidance 7.5, the paper's prompts; median seconds "
          f"per frame over {meta['rounds']} interleaved round(s) (`tools/diffuse/bench_regen_cpu.sh`).\n")
    print("| settings | implementation | s/frame | ours / diffusers | vs paper settings (same implementation) |"
          " whole sample, poor frames only |")
    print("| --- | --- | --- | --- | --- | --- |")
    for (setting, impl), s in sorted(med.items()):
        r = next(x for x in runs if x["setting"] == setting and x["impl"] == impl)
        desc = (f"{r['steps']} {r.get('scheduler', 'unipc')} steps, CFG to {r.get('guidance_end', 1.0)}, "
                f"ControlNet {r.get('control_guidance', [0.0, 1.0])}")
        vs_diff = f"{s / med[(setting, 'diffusers')]:.2f}" if impl == "gait" and (setting, "diffusers") in med else "-"
        paper = med.get(("paper", impl))
        vs_paper = f"{s / paper:.2f}" if paper else "-"
        print(f"| {setting}: {desc} | {impl} | {s:.1f} | {vs_diff} | {vs_paper} | {poor * s / 60:.0f} min |")
    print(f"\nWhole sample: {poor} of its {total} frames regenerated (`[selection] mode = \"poor\"`, counts from "
          f"{source}); regenerating all {total} frames takes {total / poor:.1f}x as long.")


if __name__ == "__main__":
    main()
