"""Faults on the real one-node Slurm of the tests (tools/batch/slurm.sh): the node set down while
tasks run (Slurm kills and requeues them), and Slurm's time-limit warning (SIGUSR1, which the
batch asks for with --signal) after which a task requeues itself. The batch must finish by
itself (`gait batch --wait` exits 0) with every row the undisturbed run's results."""
import json
import os
import socket
import shutil
import subprocess
import sys
import time

import races
import runs


def _scontrol(*args):
    return subprocess.run(["scontrol", *args], capture_output=True, text=True)


def _tasks(job):
    """(task id, state) of a job array's tasks in the queue."""
    q = subprocess.run(["squeue", "-h", "-r", "-o", "%i %T", "-j", job], capture_output=True, text=True)
    return [tuple(l.split()) for l in q.stdout.splitlines() if l.strip()]


def _running(job):
    return [t for t, s in _tasks(job) if s == "RUNNING"]


def _restarts(job):
    """Requeues so far, summed over the job array's tasks (`scontrol show job`'s Restarts=)."""
    shown = _scontrol("show", "job", job).stdout
    return sum(int(w.split("=")[1]) for w in shown.split() if w.startswith("Restarts="))


def _nudge(job):
    """A requeued task waits ~2 minutes (Slurm's own delay) before it may start again; in the
    quick mode it is let start now. Nothing else about the requeue changes."""
    for t, s in _tasks(job):
        if s == "PENDING":
            _scontrol("update", f"jobid={t}", "starttime=now")


def _row_sets(r):
    """Each row its own seed: rows of one pipeline would share every cache entry, so the
    regeneration could end (and the tasks with nothing left to interrupt) before the last event."""
    return [f"regenerator.seed={r + 1}"]


def _references(gait, work, n_rows):
    """Each row's undisturbed run, outside Slurm, side by side, with the study row's settings:
    its `set` column and its `view` (races.write_study's "left")."""
    refs = [work / f"undisturbed-slurm-{r + 1}" for r in range(n_rows)]
    procs = []
    for r, ref in enumerate(refs):
        shutil.rmtree(ref, ignore_errors=True)
        procs.append(gait.start(ref, [*_row_sets(r), 'kinematics.view="left"']))
    for p in procs:
        _, err = p.communicate()
        if p.returncode != 0:
            sys.exit(f"inject: an undisturbed run failed: {err.decode()[-500:]}")
    return refs


def _warn(task):
    """Slurm's time-limit warning to a task's batch shell. A task between states (just started
    or requeued) answers "Job can not be altered now, try again later": so it is tried again."""
    for _ in range(50):
        sent = subprocess.run(["scancel", "--signal=USR1", "--batch", task], capture_output=True, text=True)
        if sent.returncode == 0 or task not in _running(task.split("_")[0]):
            return
        time.sleep(0.2)


def run(gait, work, events, quick, log):
    """A study of `events + 1` rows on Slurm; `events` faults, alternating node-down and
    time-limit warnings, each while a task runs, has made progress since the last and still has
    frames to redraw (so the fault interrupts work and the task must requeue)."""
    n_rows = events + 1
    refs = _references(gait, work, n_rows)
    study = races.write_study(gait, work / "slurm-study.csv", n_rows, _row_sets)
    total = n_rows * gait.frames
    out = work / "slurm"
    batch = subprocess.Popen(
        races.batch_args(gait, study, out, ["--executor", "slurm", "--wait"]),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    jobs = out / "batch" / "jobs.json"
    runs.wait_for(lambda: jobs.exists() and json.loads(jobs.read_text())["runs"], batch, timeout=60)
    job = json.loads(jobs.read_text())["runs"][0]["id"]
    node = socket.gethostname().split(".")[0]
    rows = []
    for i in range(events):
        kind = "node down" if i % 2 == 0 else "time-limit warning"
        # Some progress first, so the fault interrupts work (a new entry since the last event).
        before = runs.count(out / "cache", "regenerator")
        hit = runs.wait_for(
            lambda: _running(job) and before < runs.count(out / "cache", "regenerator") < total,
            batch, timeout=600, every=0.2,
        )
        row = {"event": kind, "tasks_running": _running(job), "redrawn": runs.count(out / "cache", "regenerator")}
        restarts_before = _restarts(job)
        if not hit:
            row["ok"] = False
            row["why"] = (f"no task was redrawing frames ({row['redrawn']} of {total} redrawn, "
                          f"batch exit {batch.poll()})")
            rows.append(row)
            log(f"slurm {i + 1}/{events}: {kind}: FAILED, {row['why']}")
            continue
        if kind == "node down":
            _scontrol("update", f"nodename={node}", "state=down", "reason=fault-injection")
            time.sleep(3)
            _scontrol("update", f"nodename={node}", "state=resume")
        else:
            for t in row["tasks_running"]:
                _warn(t)
        # Requeued: Restarts grows and the tasks that ran are pending again. Waited for as such:
        # the array's tasks that have not started yet are pending too, so "a task is pending"
        # said nothing, and on a slow machine a task's own requeue (after its frame in flight)
        # came after the 2 s this once waited. Then the old instances' clean-up on the node:
        # a requeued task let start at once (the nudge below) failed there in 0 s.
        ran = set(row["tasks_running"])
        runs.wait_for(
            lambda: _restarts(job) > restarts_before
            and all(s == "PENDING" for t, s in _tasks(job) if t in ran),
            timeout=120, every=0.5,
        )
        time.sleep(3)
        row["restarts"] = _restarts(job) - restarts_before
        if quick:
            _nudge(job)
        row["ok"] = row["restarts"] > 0
        log(f"slurm {i + 1}/{events}: {kind} while {' '.join(row['tasks_running'])} ran: "
            f"{row['redrawn']} of {total} frames redrawn, requeued (restarts {row['restarts']})")
        rows.append(row)
    end = time.monotonic() + 1800
    while batch.poll() is None and time.monotonic() < end:
        if quick:
            _nudge(job)
        time.sleep(2)
    code = batch.wait()
    names = [f"S01_{r + 1}_left_sports2d-demo" for r in range(n_rows)]
    diffs = {n: runs.differences(ref, out / "runs" / n) for n, ref in zip(names, refs)}
    bad = runs.bad_entries(out / "cache")
    finished = code == 0 and not any(diffs.values()) and not bad
    for row in rows:
        row["batch_exit"] = code
        row["ok"] = row["ok"] and finished
    log(f"slurm batch: `gait batch --wait` exit {code}, rows differing "
        f"{[n for n, d in diffs.items() if d]}, {len(bad)} bad entries -> {'ok' if finished else 'FAILED'}")
    if not finished:
        log(batch.stderr.read()[-2000:])
    return rows


def available():
    return bool(os.environ.get("SLURM_CONF"))
