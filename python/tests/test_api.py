"""gait.run, gait.load, gait.kin and gait.Config against the `gait` command and the files it writes."""

import json
import pathlib
import re
import shutil
import subprocess
import urllib.request

import pandas as pd
import pytest

from conftest import (
    ROOT,
    SUBJECT_KEYPOINTS,
    TABLES,
    assert_frames_equal,
    cli,
    cli_env,
    compare_run_dirs,
    gait_bin,
    read_dlc,
)


def test_run_tables_equal_the_csv_files(clip_run):
    run = clip_run
    assert isinstance(run.dir, pathlib.Path) and run.dir.is_dir()
    for name in TABLES:
        table = getattr(run, name)
        if name.startswith("frontal_"):
            # A side view has no frontal tables.
            assert table is None and not (run.dir / f"{name}.csv").exists(), name
            continue
        assert isinstance(table, pd.DataFrame), name
        assert_frames_equal(table, pd.read_csv(run.dir / f"{name}.csv"), name)
    assert list(run.angles.columns) == [
        "frame", "time_s", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
        "right_ankle",
    ]
    assert len(run.angles) == 60
    assert_frames_equal(run.scores, pd.read_csv(run.dir / "scores.csv"), "scores")


def test_run_keypoints_in_deeplabcut_layout(clip_run):
    kp = clip_run.keypoints
    assert list(kp.columns.names) == ["scorer", "bodyparts", "coords"]
    assert list(kp.index) == list(range(60))
    parts = list(dict.fromkeys(kp.columns.get_level_values("bodyparts")))
    assert parts == clip_run.manifest["keypoint_names"]
    assert parts[:3] == ["nose", "neck", "left_shoulder"]
    assert set(kp.columns.get_level_values("coords")) == {"x", "y", "likelihood"}
    assert_frames_equal(kp, read_dlc(clip_run.dir / "keypoints.csv"), "keypoints")


def test_run_manifest_is_run_json(clip_run):
    manifest = clip_run.manifest
    assert manifest == json.loads((clip_run.dir / "run.json").read_text())
    assert manifest["frames_processed"] == 60
    assert manifest["config"]["input"]["last_frame"] == 59


def test_load_gives_the_same_run(clip_run, gait):
    loaded = gait.load(clip_run.dir)
    assert loaded.dir == clip_run.dir
    assert loaded.manifest == clip_run.manifest
    for name in TABLES + ("scores",):
        assert_frames_equal(getattr(loaded, name), getattr(clip_run, name), name)
    assert_frames_equal(loaded.keypoints, clip_run.keypoints, "keypoints")
    # A path given as a str works as well.
    assert_frames_equal(gait.load(str(clip_run.dir)).angles, clip_run.angles, "angles")


def test_run_writes_what_the_command_writes(clip_runs):
    cli_dir, run = clip_runs
    cli_names = sorted(p.name for p in cli_dir.iterdir() if p.is_file())
    assert "keypoints.csv" in cli_names and "run.json" in cli_names
    assert compare_run_dirs(cli_dir, run.dir) == []
    # What run.json may differ in: how the run was started and how long it took.
    from_cli = json.loads((cli_dir / "run.json").read_text())
    assert from_cli["command"][1:3] == ["run", "--input"]
    assert run.manifest["frames_from_cache"] == from_cli["frames_from_cache"] == 0


def test_kin_on_the_runs_keypoints_gives_its_angles(clip_run, gait):
    fps = clip_run.manifest["input"]["fps"]
    kin = gait.kin(clip_run.keypoints, fps=fps)
    assert_frames_equal(kin.angles, clip_run.angles, "angles")
    # ... and from the CSV as pandas reads it.
    kin_csv = gait.kin(read_dlc(clip_run.dir / "keypoints.csv"), fps=fps)
    assert_frames_equal(kin_csv.angles, clip_run.angles, "angles from keypoints.csv")


@pytest.mark.parametrize(
    "keypoints_csv, fps, read",
    [
        # With walking bouts, events and accepted cycles: every table filled. Its first frame has
        # no keypoint, which pd.read_csv(header=[0, 1, 2]) would take for index names.
        (SUBJECT_KEYPOINTS, 30, read_dlc),
        # As the docs say: pd.read_csv(path, header=[0, 1, 2], index_col=0).
        (
            ROOT / "tests" / "data" / "fukuchi2018" / "keypoints.csv",
            150,
            lambda path: pd.read_csv(path, header=[0, 1, 2], index_col=0),
        ),
        # A front view (issue 38): the frontal tables as DataFrames too.
        (
            ROOT / "tests" / "data" / "frontal" / "gaitkit_pd_anterior" / "keypoints.csv",
            150,
            read_dlc,
        ),
    ],
    ids=["sample-subject", "fukuchi2018", "gaitkit-pd-anterior"],
)
def test_kin_equals_the_kin_command(gait, tmp_path, keypoints_csv, fps, read):
    """gait.kin on a DeepLabCut table writes the files `gait kin` writes, and its tables are theirs."""
    # Each into the same folder path in turn: the report names its folder.
    cli("kin", "--keypoints", keypoints_csv, "--fps", fps, "--out", tmp_path / "out")
    shutil.move(str(tmp_path / "out"), str(tmp_path / "cli"))
    run = gait.kin(read(keypoints_csv), fps=fps, out=tmp_path / "out")
    assert run.dir == tmp_path / "out"
    frontal = "frontal" in str(keypoints_csv)
    for name in TABLES:
        table = getattr(run, name)
        if name.startswith("frontal_") and not frontal:
            assert table is None, name
            continue
        assert_frames_equal(table, pd.read_csv(run.dir / f"{name}.csv"), name)
    # kin.json names the keypoints for `gait review`: the command's file, gait.kin's table kept
    # as keypoints.csv in the folder.
    assert compare_run_dirs(tmp_path / "cli", run.dir, skip=("kin.json", "keypoints.csv")) == []
    manifest = json.loads((run.dir / "kin.json").read_text())
    assert pathlib.Path(manifest["keypoints"]) == (run.dir / "keypoints.csv").resolve()
    assert manifest["fps"] == fps and manifest["tool"].startswith("gait.kin")
    assert len(run.events) > 4
    if frontal:
        assert set(run.frontal_cycles["side"]) == {"left", "right"}
        assert set(run.frontal_cycles["measure"]) >= {"pelvic_obliquity", "hip_adduction"}
        assert (run.frontal_feet["measure"] == "step_width").sum() > 2
    if keypoints_csv == SUBJECT_KEYPOINTS:
        assert len(run.cycles) > 100 and set(run.cycles["side"]) == {"left", "right"}
        assert run.cycle_quality["accepted"].dtype == bool


def test_kin_takes_config_and_set(gait, tmp_path):
    keypoints = read_dlc(SUBJECT_KEYPOINTS)
    linear = gait.kin(keypoints, fps=30, set={"postprocess.filter": "none"})
    cli(
        "kin", "--keypoints", SUBJECT_KEYPOINTS, "--fps", "30", "--out", tmp_path / "cli",
        "--set", 'postprocess.filter="none"',
    )
    assert_frames_equal(linear.angles, pd.read_csv(tmp_path / "cli" / "angles.csv"), "angles")
    cfg = gait.Config.load().set("postprocess.filter", "none")
    assert_frames_equal(gait.kin(keypoints, fps=30, config=cfg).angles, linear.angles, "angles")


def test_config_load_set_to_toml(gait, clip_run):
    default = gait.Config.load()
    text = default.to_toml()
    # backend = "auto" is decided when the config is read: ort where ONNX Runtime loads.
    assert "[pose]" in text and re.search(r'backend = "(ort|candle)"', text)
    other = "candle" if 'backend = "ort"' in text else "ort"
    cfg = gait.Config.load()
    assert cfg.set("pose.backend", other) is cfg
    assert f'backend = "{other}"' in cfg.to_toml()
    assert f'backend = "{other}"' not in gait.Config.load().to_toml()
    # Values of every TOML kind.
    cfg.set("input.last_frame", 59).set("postprocess.cutoff_hz", 5.5).set("run.cache", False)
    text = cfg.to_toml()
    assert "last_frame = 59" in text and "cutoff_hz = 5.5" in text and "cache = false" in text
    # A config file, and a run's run.json (to repeat it).
    zero_shot = gait.Config.load(ROOT / "configs" / "zero-shot-canny.toml").to_toml()
    assert 'kind = "canny"' in zero_shot
    again = gait.Config.load(clip_run.dir / "run.json").to_toml()
    assert "last_frame = 59" in again


def test_exceptions_are_exported(gait):
    for name in ("ConfigError", "InputError", "StageError", "OutputError"):
        cls = getattr(gait, name)
        assert issubclass(cls, gait.GaitError) and cls is not gait.GaitError
    assert issubclass(gait.GaitError, Exception)
    assert isinstance(gait.__version__, str) and gait.__version__


def test_config_sets_a_python_stage_in_one_call(gait):
    # One key at a time could not be valid: a python stage needs module and class with its kind.
    cfg = gait.Config.load().set(
        {"pose.kind": "python", "pose.module": "gait_test_constant", "pose.class": "ConstantPose"}
    )
    text = cfg.to_toml()
    assert 'kind = "python"' in text and 'module = "gait_test_constant"' in text
    with pytest.raises(gait.ConfigError):
        gait.Config.load().set("pose.kind", "python")


def test_visit_runs_combines_a_front_and_a_side_view(gait, tmp_path):
    """gait.visit_runs (issue 39): the Parkinson's walk seen from the front and from its right
    side, each through gait.kin, combined into one visit with its checklist as DataFrames."""
    data = ROOT / "tests" / "data"
    front = gait.kin(read_dlc(data / "frontal" / "gaitkit_pd_anterior" / "keypoints.csv"), fps=150,
                     out=tmp_path / "front", set={"kinematics.view": "anterior"})
    side = gait.kin(read_dlc(data / "gaitkit_pd" / "keypoints.csv"), fps=150,
                    out=tmp_path / "side", set={"kinematics.view": "right"})
    v = gait.visit_runs(tmp_path / "visit", [("anterior", front), ("right", side)],
                        set={"kinematics.prosthetic_side": "right"}, subject="PD", session="1")
    assert v.report.is_file() and len(v.passes) == 2
    rows = v.checklist.set_index(["item", "side"])
    # Each item from the view that judges it: frontal items from the front, knee from the side.
    assert rows.loc[("hip_hiking", "right"), "verdict"] in ("present", "absent")
    assert "anterior view" in rows.loc[("hip_hiking", "right"), "pass"]
    assert rows.loc[("excessive_knee_flexion_stance", "right"), "verdict"] in ("present", "absent")
    assert "right view" in rows.loc[("excessive_knee_flexion_stance", "right"), "pass"]
    assert set(v.cycles["plane"]) == {"sagittal", "frontal"}
    assert (v.spatiotemporal["parameter"] == "stride_time").any()
    with pytest.raises(gait.InputError, match="view `sideways`"):
        gait.visit_runs(tmp_path / "bad", [("sideways", front)])


def test_a_gait_kin_folder_opens_in_gait_review(gait, tmp_path):
    """gait.kin's folder opens as `gait review DIR` (the command its checklist's links run), with
    the events of its events.csv: kin.json names the table kept as keypoints.csv."""
    keypoints = read_dlc(SUBJECT_KEYPOINTS)
    run = gait.kin(keypoints, fps=30, out=tmp_path / "kin",
                   set={"kinematics.frame_size": [1768, 994], "report.pdf": False})
    review = subprocess.Popen([str(gait_bin()), "review", str(run.dir)], cwd=ROOT, env=cli_env(),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = review.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:"), (url, review.stderr.read() if review.poll() else "")
        base, token = url.split("?")[0].rstrip("/"), url.split("token=")[1]
        with urllib.request.urlopen(f"{base}/api/analysis?token={token}", timeout=60) as reply:
            data = json.loads(reply.read())
    finally:
        review.kill()
        review.wait()
    assert len(data["events"]) == len(run.events) > 4
