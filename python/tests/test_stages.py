"""Stages written in Python (`kind = "python"`), run by gait.run and by the `gait` command.

The stage modules are in python/tests/stages/ (on sys.path here, on PYTHONPATH for the command).
"""

import csv
import json
import pathlib
import shutil
import subprocess
import tempfile

import numpy as np
import pytest

from conftest import (
    CLIP,
    CLIP_SETS,
    ROOT,
    assert_frames_equal,
    cli,
    cli_env,
    compare_run_dirs,
    error_lines,
    gait_bin,
    read_dlc,
)

import gait_test_constant

FINAL_NAMES = (
    "keypoints.csv",
    "keypoints_filtered.csv",
    "angles.csv",
    "events.csv",
    "cycles.csv",
    "run.json",
    "report.html",
    "report.pdf",
    "overlay.mp4",
)

CONSTANT = {
    "pose.kind": "python",
    "pose.module": "gait_test_constant",
    "pose.class": "ConstantPose",
}


def stage_sets(sets):
    """A {key: value} of strings as the command's --set arguments."""
    args = []
    for key, value in sets.items():
        args += ["--set", f"{key}={value}"]
    return args


def assert_constant_keypoints(kp, frames):
    pose = gait_test_constant.POSE
    parts = list(dict.fromkeys(kp.columns.get_level_values(1)))
    assert len(parts) == 15 + 33
    native = parts[15:]
    assert native[0] == "bp_nose" and native[23] == "bp_left_hip"
    assert all(name.startswith("bp_") for name in native)
    assert list(kp.index) == list(frames)
    scorer = kp.columns.get_level_values(0)[0]
    for i, name in enumerate(native):
        for j, coord in enumerate(("x", "y", "likelihood")):
            values = kp[(scorer, name, coord)].to_numpy()
            np.testing.assert_allclose(values, pose[i, j], atol=1e-6, err_msg=f"{name}/{coord}")
    # The canonical names come from the landmarks as the built-in BlazePose maps them.
    for canonical, landmark in (("left_hip", 23), ("right_knee", 26), ("left_heel", 29), ("right_toe", 32)):
        np.testing.assert_allclose(kp[(scorer, canonical, "x")], pose[landmark, 0], atol=1e-6)
        np.testing.assert_allclose(kp[(scorer, canonical, "y")], pose[landmark, 1], atol=1e-6)
    neck = (pose[11, :2] + pose[12, :2]) / 2
    np.testing.assert_allclose(kp[(scorer, "neck", "x")], neck[0], atol=1e-6)
    np.testing.assert_allclose(kp[(scorer, "neck", "y")], neck[1], atol=1e-6)


@pytest.fixture(scope="module")
def constant_runs(tmp_path_factory, gait, video):
    """The constant stage on the clip by the command (--set) and by gait.run (a gait.Config of a
    config file that names only the stage), each into the same folder path in turn."""
    base = tmp_path_factory.mktemp("constant")
    out = base / "run"
    cli("run", "--input", video, "--out", out, "--no-progress", *CLIP_SETS, *stage_sets(CONSTANT))
    shutil.move(str(out), str(base / "cli"))
    toml = base / "constant.toml"
    toml.write_text('[pose]\nkind = "python"\nmodule = "gait_test_constant"\nclass = "ConstantPose"\n')
    config = gait.Config.load(toml)
    run = gait.run(video, out=out, config=config, set=dict(CLIP), progress=False)
    return base / "cli", run


def test_constant_stage_from_the_command(constant_runs):
    cli_dir, _ = constant_runs
    assert_constant_keypoints(read_dlc(cli_dir / "keypoints.csv"), range(60))


def test_constant_stage_from_python(constant_runs):
    cli_dir, run = constant_runs
    assert_constant_keypoints(run.keypoints, range(60))
    assert_constant_keypoints(read_dlc(run.dir / "keypoints.csv"), range(60))
    assert run.manifest["stages"]["pose"]["kind"] == "python"
    assert compare_run_dirs(cli_dir, run.dir) == []
    # The stage's source is in run.json's checksums (an edited stage is run again).
    assert "gait_test_constant.py" in (run.dir / "run.json").read_text()


def test_stage_options_and_a_temporary_folder(gait, video):
    sets = [f"{k}={v}" for k, v in CONSTANT.items()] + [
        "input.last_frame=7",
        "pose.options={ shift_x = 10.5 }",
    ]
    run = gait.run(video, set=sets, progress=False)
    try:
        assert pathlib.Path(tempfile.gettempdir()) in run.dir.parents
        kp = run.keypoints
        scorer = kp.columns.get_level_values(0)[0]
        np.testing.assert_allclose(
            kp[(scorer, "bp_nose", "x")], gait_test_constant.POSE[0, 0] + 10.5, atol=1e-6
        )
        assert list(kp.index) == list(range(8))
    finally:
        shutil.rmtree(run.dir, ignore_errors=True)


def test_python_edge_and_regenerator_change_nothing(gait, video, clip_run, tmp_path):
    """An identity regenerator fed by a Python edge stage: the pose model sees the frames
    unchanged, so the keypoints are the default run's."""
    sets = {
        **CLIP,
        "edge.kind": "python",
        "edge.module": "gait_test_identity",
        "edge.class": "GrayEdges",
        "regenerator.kind": "python",
        "regenerator.module": "gait_test_identity",
        "regenerator.class": "Identity",
        "regenerator.options": {"want_edges": True},
    }
    run = gait.run(video, out=tmp_path / "run", set=sets, progress=False)
    stages = run.manifest["stages"]
    assert stages["edge"]["kind"] == "python" and stages["regenerator"]["kind"] == "python"
    assert stages["regenerator"]["computed"] > 0
    assert (run.dir / "keypoints.csv").read_bytes() == (clip_run.dir / "keypoints.csv").read_bytes()
    assert_frames_equal(run.angles, clip_run.angles, "angles")


# (module, class, frame the message names or None for a load error, words in the message)
FAULTY = [
    ("gait_test_faulty", "WrongShape", 0, ["estimate returned bad data", "shape (17, 3), expected (33, 3)"]),
    ("gait_test_faulty", "IntDtype", 0, ["dtype int64", "float"]),
    ("gait_test_faulty", "NaNPose", 0, ["keypoint 25", "NaN", "finite"]),
    ("gait_test_faulty", "Raises", 0, ["estimate raised", "RuntimeError: the model is on fire", "gait_test_faulty.py:"]),
    ("gait_test_faulty", "WrongCount", 0, ["3 items for 4 frames"]),
    ("gait_test_faulty", "KeepsFrame", 0, ["kept a frame", "frame.copy()"]),
    ("gait_test_faulty", "LateBadItem", 10, ["shape (33, 2), expected (33, 3)"]),
    ("gait_test_faulty", "LateRaise", 4, ["KeyError", "lost"]),
    ("gait_test_faulty", "NoMethod", None, ["no method `estimate`"]),
    ("gait_test_faulty", "BadLayout", None, ["halpe26", "blazepose33"]),
    ("gait_test_faulty", "RaisesInInit", None, ["ValueError: no weights"]),
    ("gait_test_faulty", "NoSuchClass", None, ["has no class `NoSuchClass`"]),
    ("gait_test_broken_import", "Whatever", None, ["cannot import", "gait_test_no_such_module", "PYTHONPATH"]),
    ("gait_test_no_such_module", "Whatever", None, ["cannot import", "No module named"]),
]


def assert_nothing_final(out):
    out = pathlib.Path(out)
    if out.is_dir():
        written = [name for name in FINAL_NAMES if (out / name).exists()]
        assert written == [], written


def assert_names_stage(message, module, cls, frame):
    assert "\n" not in message, repr(message)
    assert f"python stage {module}.{cls}" in message, message
    if frame is not None:
        assert f"frame {frame}" in message, message


@pytest.mark.parametrize("module, cls, frame, words", FAULTY, ids=[f"{m}.{c}" for m, c, _, _ in FAULTY])
def test_faulty_stage(gait, video, tmp_path, module, cls, frame, words):
    sets = {**CLIP, "pose.kind": "python", "pose.module": module, "pose.class": cls}
    with pytest.raises(gait.StageError) as caught:
        gait.run(video, out=tmp_path / "py", set=sets, progress=False)
    message = str(caught.value)
    assert_names_stage(message, module, cls, frame)
    for word in words:
        assert word in message, message
    assert_nothing_final(tmp_path / "py")

    proc = cli(
        "run", "--input", video, "--out", tmp_path / "cli", "--no-progress", *stage_sets(sets),
        check=False,
    )
    assert proc.returncode == 2, proc.stderr
    lines = error_lines(proc.stderr)
    assert len(lines) == 1, proc.stderr
    assert lines[0] == "error: " + message
    assert_nothing_final(tmp_path / "cli")


def test_the_command_finds_numpy_in_the_active_venv_only(video, tmp_path):
    """Without $VIRTUAL_ENV the embedded interpreter has only its own packages: either numpy is
    there, or the run stops with one line that says to install it."""
    env = cli_env()
    del env["VIRTUAL_ENV"]
    proc = subprocess.run(
        [str(gait_bin()), "run", "--input", str(video), "--out", str(tmp_path / "run"),
         "--no-progress", "--set", "input.last_frame=3", *stage_sets(CONSTANT)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
    )
    if proc.returncode == 0:
        assert (tmp_path / "run" / "keypoints.csv").exists()
    else:
        assert proc.returncode == 2, proc.stderr
        lines = error_lines(proc.stderr)
        assert len(lines) == 1 and "pip install numpy" in lines[0], proc.stderr
        assert_nothing_final(tmp_path / "run")


def test_mediapipe_example_stage(gait, video, tmp_path):
    """examples/python/mediapipe_pose.py (configs/python-mediapipe.toml): mediapipe's own BlazePose
    from the venv, by gait.run and by the command (which finds mediapipe through $VIRTUAL_ENV)."""
    config = ROOT / "configs" / "python-mediapipe.toml"
    frames = {"input.first_frame": 100, "input.last_frame": 107}
    cli(
        "run", "--config", config, "--input", video, "--out", tmp_path / "out", "--no-progress",
        *stage_sets(frames),
    )
    shutil.move(str(tmp_path / "out"), str(tmp_path / "cli"))
    run = gait.run(video, out=tmp_path / "out", config=config, set=frames, progress=False)
    kp = run.keypoints
    assert list(kp.index) == list(range(100, 108))
    scorer = kp.columns.get_level_values(0)[0]
    assert (kp[(scorer, "left_knee", "likelihood")] > 0.5).all()
    assert (kp[(scorer, "bp_right_ankle", "likelihood")] > 0.5).all()
    assert (tmp_path / "cli" / "keypoints.csv").read_bytes() == (run.dir / "keypoints.csv").read_bytes()


LOWER_LIMB = [
    f"{side}_{part}" for side in ("left", "right") for part in ("hip", "knee", "ankle", "heel", "toe")
]


def test_mediapipe_stage_equals_the_built_in_blazepose(gait, video, tmp_path):
    """Issue 31's check of the Python boundary on real frames: mediapipe's own BlazePose as a Python
    stage against the built-in BlazePose run as mediapipe's video mode (its detector's best person,
    tracking with the crop filter of mediapipe's graph, `pose.roi_filter = "mediapipe"`), on the
    frames where the walker is the one in view (59-192; before, mediapipe follows the man on the box,
    which gait's subject pass would not). Lower-limb keypoints within 1 px (median), every gait event
    within 1 frame."""
    frames = {"input.first_frame": 59, "input.last_frame": 192, "subject.enabled": False}
    built_in = gait.run(
        video,
        out=tmp_path / "built-in",
        set={**frames, "pose.person": "most_confident", "pose.roi_filter": "mediapipe"},
        progress=False,
    )
    python = gait.run(
        video,
        out=tmp_path / "python",
        config=ROOT / "configs" / "python-mediapipe.toml",
        set=frames,
        progress=False,
    )
    a, b = built_in.keypoints, python.keypoints
    scorer_a, scorer_b = a.columns[0][0], b.columns[0][0]
    distances = []
    for name in LOWER_LIMB:
        dx = a[(scorer_a, name, "x")] - b[(scorer_b, name, "x")]
        dy = a[(scorer_a, name, "y")] - b[(scorer_b, name, "y")]
        distances.extend(d for d in (dx**2 + dy**2) ** 0.5 if d == d)
    assert len(distances) >= 10 * 120, len(distances)
    median = sorted(distances)[len(distances) // 2]
    assert median <= 1.0, median

    def events(run):
        return [(e.side, e.event, int(e.frame)) for e in run.events.itertuples()]

    ea, eb = events(built_in), events(python)
    assert len(ea) >= 10 and len(ea) == len(eb), (ea, eb)
    for side, kind, frame in ea:
        assert any(s == side and k == kind and abs(f - frame) <= 1 for s, k, f in eb), (side, kind, frame, eb)


def test_a_top_down_coco17_stage_follows_the_subject(video, tmp_path):
    """Issue 37: a Python pose stage that takes the subject's boxes (examples/python/mediapipe_coco17.py,
    mediapipe on each box, written as COCO-17: no heels, no toes) follows the walker the subject pass
    chose (listed by the built-in BlazePose detector), and its events, from the ankles, agree with the
    built-in BlazePose run's: at least 12 of its 14 within a frame, and the same accepted cycles."""
    fast = ["--no-progress", "--set", "report.overlay=false", "--set", "report.pdf=false"]
    cli("run", "--input", video, "--out", tmp_path / "built-in", *fast)
    cli(
        "run", "--input", video, "--out", tmp_path / "coco17", *fast,
        "--set", "pose.kind=python", "--set", "pose.module=mediapipe_coco17",
        "--set", "pose.class=MediapipeCoco17",
    )
    manifest = json.loads((tmp_path / "coco17" / "run.json").read_text())
    assert manifest["stages"]["subject"]["kind"].startswith("blazepose detector"), manifest["stages"]
    assert manifest["subject"]["reason"].startswith("walker"), manifest["subject"]
    assert manifest["extra"]["kinematics"]["event_keypoints"]["left"] == "left_ankle/left_ankle"

    def events(folder):
        with open(folder / "events.csv", newline="") as f:
            return [(r["side"], r["event"], int(r["frame"])) for r in csv.DictReader(f)]

    def cycles(folder):
        with open(folder / "cycle_quality.csv", newline="") as f:
            return [
                (r["side"], int(r["first_frame"]), int(r["last_frame"]))
                for r in csv.DictReader(f)
                if r["accepted"] == "true"
            ]

    a, b = events(tmp_path / "built-in"), events(tmp_path / "coco17")
    assert len(a) == 14, a
    near = [e for e in a if any(s == e[0] and k == e[1] and abs(f - e[2]) <= 1 for s, k, f in b)]
    assert len(near) >= 12, (a, b)
    ca, cb = cycles(tmp_path / "built-in"), cycles(tmp_path / "coco17")
    assert len(ca) == len(cb) == 5, (ca, cb)
    assert all(x[0] == y[0] and abs(x[1] - y[1]) <= 1 and abs(x[2] - y[2]) <= 1 for x, y in zip(ca, cb)), (ca, cb)
