"""Kills at random points of every step of a run (SIGKILL and SIGTERM), each followed by the
check that nothing half-written is under a final name and every cache entry is whole, then a
rerun that must give the undisturbed run's results."""
import json
import random
import signal
import time

import runs

STEPS = ["subject", "regeneration", "poses", "kinematics", "report", "export"]


def _trigger(step, out, done, rng, ref_seconds):
    """When to send the signal during `step`: a predicate on the run folder, and a delay after it
    holds. `done`: the entries of each stage the undisturbed run cached (the frames with the
    subject in view). The step actually hit is read from the folder afterwards (`_hit`)."""
    cache = out / "cache"

    def partway(stage):
        k = rng.randint(1, max(1, done[stage] - 1))
        return lambda: runs.count(cache, stage) >= k

    if step == "subject":
        return partway("subject"), 0.0
    if step == "regeneration":
        return partway("regenerator"), 0.0
    if step == "poses":
        return partway("pose"), 0.0
    if step == "kinematics":
        return (lambda: runs.count(cache, "pose") >= done["pose"]), rng.uniform(0, 0.3)
    if step == "report":
        return (lambda: (out / "angles.mot").exists()), rng.uniform(0, ref_seconds)
    return (lambda: (out / "keypoints_filtered.csv").exists()), rng.uniform(0, 0.05)


def _hit(out, done):
    """The step a stopped run was in, from what it left."""
    cache = out / "cache"
    for step, finished in [
        ("subject", runs.count(cache, "subject") >= done["subject"]),
        # A batch's frames are redrawn, then their poses found: the two steps interleave.
        ("regeneration and poses", runs.count(cache, "pose") >= done["pose"]),
        ("kinematics", (out / "spatiotemporal.csv").exists()),
        ("export", (out / "angles.mot").exists()),
        ("report: overlay.mp4", (out / "overlay.mp4").exists()),
        ("report: html and pdf", (out / "report.pdf").exists()),
    ]:
        if not finished:
            return step
    return "after the end"


def run(gait, ref, work, n, rng, log):
    """`n` kills, cycling through the steps and alternating SIGKILL and SIGTERM."""
    report = json.loads((ref / "run.json").read_text())["report"]["seconds"]
    ref_seconds = sum(report.values())
    done = {stage: runs.count(ref / "cache", stage) for stage in ["subject", "regenerator", "pose"]}
    rows = []
    for i in range(n):
        step = STEPS[i % len(STEPS)]
        # Alternating, and shifted each round, so every step gets both signals.
        sig = signal.SIGKILL if (i + i // len(STEPS)) % 2 == 0 else signal.SIGTERM
        out = work / f"kill{i:03d}"
        when, delay = _trigger(step, out, done, rng, ref_seconds)
        proc = gait.start(out)
        reached = runs.wait_for(when, proc)
        if reached and delay:
            time.sleep(delay)
        sent = time.monotonic()
        row = {"target": step, "signal": sig.name}
        if proc.poll() is None:
            proc.send_signal(sig)
            code = proc.wait()
            row["stop_s"] = round(time.monotonic() - sent, 3)
        else:
            code = proc.returncode
        runs.stop_group(proc)
        # Popen gives -N for a process the signal N ended; a shell says 128 + N.
        row["exit"] = 128 - code if code < 0 else code
        row["injected"] = code != 0
        row["hit"] = _hit(out, done) if row["injected"] else "after the end"
        if sig == signal.SIGTERM and row["injected"]:
            manifest = json.loads((out / "run.json").read_text()) if (out / "run.json").exists() else {}
            row["says_interrupted"] = manifest.get("status") == "interrupted"
            row["expected_exit"] = code == 143
        row["partial"] = runs.partial_files(ref, out)
        row["bad_entries"] = runs.bad_entries(out / "cache")
        code, err = gait.run(out)
        row["resumed"] = code == 0
        row["differences"] = runs.differences(ref, out) if code == 0 else [err.strip()[-300:]]
        row["ok"] = (
            row["resumed"]
            and not row["differences"]
            and not row["partial"]
            and not row["bad_entries"]
            and row.get("says_interrupted", True)
            and row.get("expected_exit", True)
        )
        log(f"kill {i + 1}/{n}: {sig.name} aimed at {step}, hit {row['hit']}, exit {row['exit']}"
            f"{', stopped in %.2f s' % row['stop_s'] if 'stop_s' in row and sig == signal.SIGTERM else ''}"
            f" -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
        rows.append(row)
    return rows
