"""Shared fixtures of the `gait` Python package's tests (run by tools/python/test.sh).

The runs use the first 60 frames of the bundled sample video (`input.last_frame = 59`), which
keeps each one to a few seconds; the `gait` command is $GAIT_BIN (default target/debug/gait).
"""

import csv
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
STAGES = pathlib.Path(__file__).resolve().parent / "stages"
VIDEO = pathlib.Path(os.path.normpath(ROOT / ".." / "shared" / "data" / "sports2d-demo.mp4"))
CLIP = {"input.last_frame": 59}
CLIP_SETS = ["--set", "input.last_frame=59"]
# A kinematics-only input with walking bouts, events and accepted cycles (230 frames, 30 fps).
SUBJECT_KEYPOINTS = ROOT / "tests" / "data" / "sample-subject" / "keypoints.csv"
TABLES = ("angles", "events", "bouts", "cycles", "cycles_all", "cycle_quality", "spatiotemporal")

EXAMPLES = ROOT / "examples" / "python"

# Python stages are imported by gait.run from this interpreter's sys.path.
for folder in (EXAMPLES, STAGES):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
# The `gait` command finds the models here unless told otherwise (tools/setup.sh does the same).
if (ROOT / "target" / "models").is_dir():
    os.environ.setdefault("GAIT_MODELS_DIR", str(ROOT / "target" / "models"))


def gait_bin():
    path = pathlib.Path(os.environ.get("GAIT_BIN", "target/debug/gait"))
    return path if path.is_absolute() else ROOT / path


def cli_env():
    """The environment of a `gait` command: the stages on PYTHONPATH, this venv's packages (numpy)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(STAGES), str(EXAMPLES)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    )
    env["VIRTUAL_ENV"] = sys.prefix
    return env


def cli(*args, check=True, timeout=600):
    """Runs `gait ARGS...` in the repository root; returns the CompletedProcess."""
    proc = subprocess.run(
        [str(gait_bin()), *map(str, args)],
        cwd=ROOT,
        env=cli_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if check and proc.returncode != 0:
        raise AssertionError(
            f"gait {' '.join(map(str, args))} exited {proc.returncode}:\n{proc.stderr}"
        )
    return proc


def error_lines(stderr):
    """stderr without the warnings a run prints as it goes."""
    return [line for line in stderr.splitlines() if not line.startswith("warning: ")]


def read_dlc(path):
    """A DeepLabCut CSV as pd.read_csv(path, header=[0, 1, 2], index_col=0) gives it.

    The three header rows are read apart: read_csv would take a first frame whose keypoints are
    all empty (`0,,,...`) for a row of index names, and the clip's first frame is such a one.
    """
    import pandas as pd

    with open(path, newline="") as f:
        header = [row for _, row in zip(range(3), csv.reader(f))]
    df = pd.read_csv(path, header=None, skiprows=3, index_col=0)
    df.index.name = None
    df.columns = pd.MultiIndex.from_arrays(
        [row[1:] for row in header], names=[row[0] for row in header]
    )
    return df


def assert_frames_equal(left, right, what=""):
    """Equal to the CSVs' printed precision (6 decimals)."""
    import pandas.testing as pdt

    try:
        pdt.assert_frame_equal(left, right, check_exact=False, atol=1e-6, rtol=0)
    except AssertionError as e:
        raise AssertionError(f"{what}: {e}") from None


def without_timing(value, drop=("command", "started_unix", "seconds", "timings")):
    """run.json without what records how the run went rather than what it found."""
    if isinstance(value, dict):
        return {k: without_timing(v, drop) for k, v in value.items() if k not in drop}
    if isinstance(value, list):
        return [without_timing(v, drop) for v in value]
    return value


def report_without_timing(text):
    """report.html without the run.json fields without_timing drops (it lists run.json)."""
    # The provenance table's start time, to the minute: two runs a few seconds apart may
    # straddle a minute (1 run in 6 did).
    text = re.sub(r"<td>Run started</td><td>[^<]*</td>", "", text)
    text = re.sub(r"&quot;command&quot;: \[.*?\],", "", text, flags=re.S)
    text = re.sub(r"&quot;seconds&quot;: \{.*?\}", "", text, flags=re.S)
    return re.sub(r"&quot;(started_unix|seconds|total_s|unaccounted_s)&quot;: [0-9.e+-]+,?", "", text)


def compare_run_dirs(a, b, skip=(), drop=("command", "started_unix", "seconds", "timings")):
    """Differences between two run folders' files, as a list of messages (empty: the same).

    Every file is compared byte for byte except run.json (without `drop`), report.html (the same
    fields removed where it lists run.json) and report.pdf (it prints those too, and its dates:
    only its presence is compared). Folders (the cache) are not compared.
    """
    a, b = pathlib.Path(a), pathlib.Path(b)
    names_a = sorted(p.name for p in a.iterdir() if p.is_file() and p.name not in skip)
    names_b = sorted(p.name for p in b.iterdir() if p.is_file() and p.name not in skip)
    if names_a != names_b:
        return [f"different files: {names_a} vs {names_b}"]
    diffs = []
    for name in names_a:
        if name == "report.pdf":
            continue
        if name == "run.json":
            ja = without_timing(json.loads((a / name).read_text()), drop)
            jb = without_timing(json.loads((b / name).read_text()), drop)
            if ja != jb:
                keys = sorted(k for k in set(ja) | set(jb) if ja.get(k) != jb.get(k))
                diffs.append(f"run.json differs in {keys}")
        elif name == "report.html":
            if report_without_timing((a / name).read_text()) != report_without_timing(
                (b / name).read_text()
            ):
                diffs.append("report.html differs")
        elif (a / name).read_bytes() != (b / name).read_bytes():
            diffs.append(f"{name} differs")
    return diffs


@pytest.fixture(scope="session", autouse=True)
def temporary_folders(tmp_path_factory):
    """gait.run(out=None) and gait.kin(out=None) folders, the notebook's kernel's too, go under
    pytest's own temporary folder rather than piling up in /tmp."""
    folder = str(tmp_path_factory.mktemp("tmp"))
    saved = os.environ.get("TMPDIR"), tempfile.tempdir
    os.environ["TMPDIR"] = folder
    tempfile.tempdir = folder
    yield folder
    if saved[0] is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = saved[0]
    tempfile.tempdir = saved[1]


@pytest.fixture(scope="session")
def gait():
    import gait as module

    return module


@pytest.fixture(scope="session")
def video():
    assert VIDEO.is_file(), f"the sample video is missing: {VIDEO}"
    return VIDEO


@pytest.fixture(scope="session")
def clip_runs(tmp_path_factory, gait, video):
    """The clip run by `gait run` and by gait.run, each into the same folder path in turn (the
    report names its folder), with no cache from before: (the CLI's folder, the gait.Run)."""
    base = tmp_path_factory.mktemp("clip")
    out = base / "run"
    cli("run", "--input", video, "--out", out, "--no-progress", *CLIP_SETS)
    shutil.move(str(out), str(base / "cli"))
    run = gait.run(str(video), out=str(out), set=dict(CLIP), progress=False)
    return base / "cli", run


@pytest.fixture(scope="session")
def clip_run(clip_runs):
    return clip_runs[1]
