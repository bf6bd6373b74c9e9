"""Ctrl-C during gait.run: KeyboardInterrupt within about a second, the cache kept, a rerun resumes."""

import json
import os
import signal
import subprocess
import sys
import time

from conftest import ROOT, cli_env, compare_run_dirs, gait_bin

SCRIPT = """
import sys, gait
gait.run(sys.argv[1], out=sys.argv[2], set={"input.last_frame": 59}, progress=True)
print("finished")
"""


def cached_frames(out, stage):
    """Frames in the cache folder of `stage` (cache/<stage>-<key>/NNNNNN.json)."""
    cache = out / "cache"
    if not cache.is_dir():
        return 0
    return sum(
        1
        for d in cache.iterdir()
        if d.is_dir() and d.name.startswith(stage)
        for f in d.iterdir()
        if f.suffix == ".json" and f.stem.isdigit()
    )


def assert_interrupted(out):
    assert not (out / "keypoints.csv").exists()
    assert not (out / "angles.csv").exists()
    if (out / "run.json").exists():
        manifest = json.loads((out / "run.json").read_text())
        assert manifest.get("status") == "interrupted", manifest
        assert manifest.get("interrupted_during"), manifest


def wait_for_pose_frames(proc, out, frames=4):
    """Waits until the pose pass has put `frames` frames in the cache."""
    deadline = time.monotonic() + 120
    while cached_frames(out, "pose-") < frames:
        assert proc.poll() is None, f"the run ended before Ctrl-C:\n{proc.communicate()}"
        assert time.monotonic() < deadline, f"no {frames} pose frames cached after 120 s"
        time.sleep(0.02)


def test_ctrl_c_stops_the_run_and_a_rerun_resumes(clip_run, video, tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(video), str(out)],
        cwd=ROOT,
        env=dict(os.environ),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # A suite started in the background by a non-interactive shell inherits SIGINT ignored,
        # and Python then installs no Ctrl-C handler; a user's terminal never does that.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        wait_for_pose_frames(proc, out)
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        stdout, stderr = proc.communicate(timeout=30)
        stopped_after = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode != 0, stdout + stderr
    assert "KeyboardInterrupt" in stderr, stderr
    assert "finished" not in stdout
    assert stopped_after < 5, f"stopped {stopped_after:.1f} s after Ctrl-C"
    # Stopped before the end: no results, a run.json that says so, frames kept in the cache.
    assert_interrupted(out)
    kept = cached_frames(out, "pose-")
    assert 4 <= kept < 60, kept

    # A rerun into the same folder takes the frames done from the cache ...
    import gait

    rerun = gait.run(video, out=out, set={"input.last_frame": 59}, progress=False)
    manifest = rerun.manifest
    assert manifest["frames_from_cache"] > 0, manifest["frames_from_cache"]
    assert manifest["stages"]["pose"]["cached"] >= kept - 4, manifest["stages"]["pose"]
    # ... and finds what a run without Ctrl-C found (the report names its folder: not compared;
    # run.json without its record of the cache use).
    drop = ("command", "started_unix", "seconds", "timings", "frames_from_cache", "cached", "computed")
    diffs = compare_run_dirs(clip_run.dir, out, skip=("report.html",), drop=drop)
    assert diffs == []
    assert json.loads((out / "run.json").read_text())["frames_processed"] == 60


def test_ctrl_c_stops_the_command(video, tmp_path):
    """The `gait` command: exit 130 (128 + SIGINT), a run.json that says interrupted."""
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [str(gait_bin()), "run", "--input", str(video), "--out", str(out), "--no-progress",
         "--set", "input.last_frame=59"],
        cwd=ROOT,
        env=cli_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for_pose_frames(proc, out)
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        _, stderr = proc.communicate(timeout=30)
        stopped_after = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, stderr
    assert stopped_after < 5, f"stopped {stopped_after:.1f} s after Ctrl-C"
    assert_interrupted(out)
    assert (out / "run.json").exists()
