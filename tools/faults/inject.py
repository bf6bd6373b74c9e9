#!/usr/bin/env python3
"""Fault injection (issue 32): kills at random points of every step, full disks, node-down and
time-limit events on Slurm, concurrent writers and corrupt cache entries, each checked against
the undisturbed run: results byte-identical (run.json and report.html without timings and
cache counts; report.pdf whole), nothing half-written under a final name, every cache entry
whole. Exits 1 when any fault lost or changed a result.

    python3 tools/faults/inject.py --gait target/debug/gait --models target/models \\
        [--mode quick|long] [--work DIR] [--seed N] [--json FILE]

quick (tools/test.sh): 12 kills on 8-frame runs; long (BENCHMARKS.md): 60 kills on 16 frames.
Both: 5 full disks, 3 Slurm events, 10 races, 20 corrupt entries. Needs root (tmpfs mounts,
the node's state) and a Slurm up (`eval "export $(bash tools/batch/slurm.sh up)"`)."""
import argparse
import json
import pathlib
import random
import shutil
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).parent))

import disk  # noqa: E402
import kills  # noqa: E402
import races  # noqa: E402
import runs  # noqa: E402
import slurm  # noqa: E402

MODES = {"quick": {"frames": 8, "kills": 12}, "long": {"frames": 16, "kills": 60}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait", required=True)
    ap.add_argument("--models", required=True)
    ap.add_argument("--mode", choices=MODES, default="quick")
    ap.add_argument("--work")
    ap.add_argument("--seed", type=int, default=32)
    ap.add_argument("--json")
    ap.add_argument("--only", help="comma-separated parts (kills,full_disk,slurm,races,corruptions), to debug one")
    a = ap.parse_args()
    if disk.needs_root() or not slurm.available():
        sys.exit("inject: needs root (tmpfs, node state) and SLURM_CONF (tools/batch/slurm.sh up)")
    mode = MODES[a.mode]
    # Absolute: the runs print their folder, and the comparisons take it out.
    work = pathlib.Path(a.work or tempfile.mkdtemp(prefix="gait-faults-")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    rng = random.Random(a.seed)
    gait = runs.Gait(pathlib.Path(a.gait).resolve(), pathlib.Path(a.models).resolve(), mode["frames"])
    started = time.monotonic()

    def log(line):
        print(f"[{time.monotonic() - started:6.0f} s] {line}", flush=True)

    ref = work / "undisturbed"
    shutil.rmtree(ref, ignore_errors=True)
    code, err = gait.run(ref)
    if code != 0:
        sys.exit(f"inject: the undisturbed run failed: {err.strip()[-500:]}")
    log(f"undisturbed run: {mode['frames']} frames -> {ref}")
    parts = {
        "kills": lambda: kills.run(gait, ref, work, mode["kills"], rng, log),
        "full_disk": lambda: disk.full_disk(gait, ref, work, log),
        "slurm": lambda: _slurm(a, mode, work, log),
        "races": lambda: races.run(gait, ref, work, log),
        "corruptions": lambda: disk.corruptions(gait, ref, work, 20, rng, log),
    }
    only = a.only.split(",") if a.only else list(parts)
    found = {name: (run() if name in only else []) for name, run in parts.items()}
    summary = _summary(found)
    for line in summary["lines"]:
        print(line)
    print(f"fault injection ({a.mode}): {time.monotonic() - started:.0f} s, work folder {work}")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps({"mode": a.mode, "seed": a.seed, **found}, indent=1))
    sys.exit(0 if summary["failed"] == 0 else 1)


def _slurm(a, mode, work, log):
    """Slurm's events need tasks that run long enough to be hit three times: three times the frames,
    each row with undisturbed runs of its own."""
    gait = runs.Gait(pathlib.Path(a.gait).resolve(), pathlib.Path(a.models).resolve(), 3 * mode["frames"])
    return slurm.run(gait, work, 3, a.mode == "quick", log)


def _summary(found):
    k = found["kills"]
    injected = [r for r in k if r["injected"]]
    hits = {}
    for r in injected:
        hits[r["hit"]] = hits.get(r["hit"], 0) + 1
    stops = [r["stop_s"] for r in injected if r["signal"] == "SIGTERM" and "stop_s" in r]
    lines = [
        f"kills: {len(injected)} injected ({len(k) - len(injected)} arrived after the run ended), "
        f"steps hit {hits}; {sum(r['resumed'] for r in injected)} resumed, "
        f"{sum(r['ok'] for r in injected)} byte-identical with nothing partial"
        + (f"; SIGTERM stopped within {max(stops):.2f} s" if stops else ""),
    ]
    failed = sum(not r["ok"] for r in injected)
    for name in ["full_disk", "slurm", "races", "corruptions"]:
        rows = found[name]
        ok = sum(r["ok"] for r in rows)
        failed += len(rows) - ok
        extra = ""
        if name == "corruptions":
            extra = f" ({sum(len(r['planted']) for r in rows)} entries)"
        lines.append(f"{name}: {len(rows)} injected{extra}, {ok} resumed byte-identical, {len(rows) - ok} lost or partial")
    lines.append(f"results lost, changed or partial: {failed}")
    return {"lines": lines, "failed": failed}


if __name__ == "__main__":
    main()
