"""Errors: the exception classes of gait, each with the `gait` command's one-line message."""

import pandas as pd
import pytest

from conftest import ROOT, SUBJECT_KEYPOINTS, cli, error_lines, read_dlc


def cli_error(*args):
    """The `gait` command's error line without "error: ", and its exit code."""
    proc = cli(*args, check=False)
    lines = error_lines(proc.stderr)
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("error: "), lines
    return lines[0][len("error: "):], proc.returncode


def one_line(exc):
    text = str(exc)
    assert text and "\n" not in text, repr(text)
    assert not text.startswith("error:"), text
    return text


@pytest.mark.parametrize(
    "sets, cli_set, words",
    [
        ({"pose.backend": "nope"}, 'pose.backend="nope"', ["nope", "candle"]),
        ({"pose.nope": 1}, "pose.nope=1", ["nope", "backend"]),
        (["input.last_frame=-3"], "input.last_frame=-3", ["last_frame"]),
    ],
)
def test_bad_set_is_a_config_error(gait, video, tmp_path, sets, cli_set, words):
    with pytest.raises(gait.ConfigError) as caught:
        gait.run(video, out=tmp_path / "py", set=sets, progress=False)
    message = one_line(caught.value)
    for word in words:
        assert word in message, message
    expected, code = cli_error("run", "--input", video, "--out", tmp_path / "cli", "--set", cli_set)
    assert message == expected
    assert code == 2
    assert not (tmp_path / "py" / "run.json").exists()


def test_config_set_checks_at_once(gait):
    cfg = gait.Config.load()
    before = cfg.to_toml()
    with pytest.raises(gait.ConfigError) as caught:
        cfg.set("pose.backend", "nope")
    assert "nope" in one_line(caught.value)
    # The bad value was not kept.
    assert cfg.to_toml() == before
    with pytest.raises(gait.ConfigError):
        gait.Config.load(ROOT / "configs" / "no-such-config.toml")


def test_missing_input_is_an_input_error(gait, tmp_path):
    missing = tmp_path / "no-such-video.mp4"
    with pytest.raises(gait.InputError) as caught:
        gait.run(missing, out=tmp_path / "py", progress=False)
    message = one_line(caught.value)
    assert str(missing) in message
    expected, code = cli_error("run", "--input", missing, "--out", tmp_path / "cli")
    assert message == expected and code == 2
    assert not (tmp_path / "py" / "keypoints.csv").exists()


def test_kin_names_the_missing_columns(gait):
    keypoints = read_dlc(SUBJECT_KEYPOINTS)
    scorer = keypoints.columns.get_level_values(0)[0]
    broken = keypoints.drop(columns=[(scorer, "left_knee", "y"), (scorer, "right_heel", "likelihood")])
    with pytest.raises(gait.InputError) as caught:
        gait.kin(broken, fps=30)
    message = one_line(caught.value)
    assert "left_knee/y" in message and "right_heel/likelihood" in message, message
    assert "left_knee/x" not in message


def test_kin_wants_deeplabcut_columns(gait):
    flat = pd.read_csv(SUBJECT_KEYPOINTS, skiprows=[0, 2])
    with pytest.raises(gait.InputError) as caught:
        gait.kin(flat, fps=30)
    assert "header=[0, 1, 2]" in one_line(caught.value)


def test_load_of_a_folder_that_is_no_run(gait, tmp_path):
    with pytest.raises(gait.InputError) as caught:
        gait.load(tmp_path)
    assert str(tmp_path) in one_line(caught.value)


def test_errors_are_gait_errors(gait, tmp_path):
    for call in (
        lambda: gait.run(tmp_path / "none.mp4", out=tmp_path / "a", progress=False),
        lambda: gait.Config.load().set("pose.backend", 3),
        lambda: gait.load(tmp_path),
    ):
        with pytest.raises(gait.GaitError) as caught:
            call()
        one_line(caught.value)
