"""gait.visit and gait.visit_runs: one session's passes combined, as `gait visit`."""

import os
import pathlib
import tempfile

from gait import _gait
from gait._config import as_sets
from gait._run import Run, _config, read_csv, run

VIEWS = ("left", "right", "anterior", "posterior")


class Visit:
    """A visit folder and its tables as pandas DataFrames.

    checklist: visit_checklist.csv (each item per side, with the pass it comes from); cycles:
    visit_cycles.csv (each side's curves from its chosen pass); spatiotemporal:
    visit_spatiotemporal.csv (timing pooled over the passes); passes: the gait.Run of each pass.
    """

    def __init__(self, dir, passes=()):
        self.dir = pathlib.Path(dir)
        self.passes = list(passes)

    def __repr__(self):
        return f"gait.Visit({str(self.dir)!r})"

    @property
    def report(self):
        return self.dir / "report.html"

    @property
    def checklist(self):
        return read_csv(self.dir / "visit_checklist.csv")

    @property
    def cycles(self):
        return read_csv(self.dir / "visit_cycles.csv")

    @property
    def spatiotemporal(self):
        return read_csv(self.dir / "visit_spatiotemporal.csv")


def visit_runs(out, runs, config=None, set=None, subject="", session="", date=""):
    """Combines earlier runs of one session: runs is a list of (view, run folder or gait.Run),
    view one of left, right, anterior, posterior."""
    path, sets = _config(config, set)
    given = [(view, r if isinstance(r, Run) else Run(r)) for view, r in runs]
    passes = [(view, os.fspath(r.dir), os.fspath(r.dir)) for view, r in given]
    _gait.visit(os.fspath(out), passes, path, sets, subject, session, date)
    return Visit(out, [r for _, r in given])


def visit(out=None, left=(), right=(), anterior=(), posterior=(), config=None, set=None,
          progress=True, models_dir=None, subject="", session="", date=""):
    """Runs each pass (a video per view, as `gait run` with kinematics.view set) into
    out/passes/N-VIEW and combines them into out, as `gait visit`."""
    if out is None:
        out = tempfile.mkdtemp(prefix="gait-visit-")
    out = pathlib.Path(out)
    todo = [(view, v) for view, videos in zip(VIEWS, (left, right, anterior, posterior))
            for v in ([videos] if isinstance(videos, (str, os.PathLike)) else videos)]
    if not todo:
        raise _gait.InputError("a visit needs at least one pass: left=, right=, anterior= or posterior= a video")
    runs = []
    for k, (view, video) in enumerate(todo, start=1):
        extra = as_sets(set) + [f'kinematics.view="{view}"']
        r = run(video, out=out / "passes" / f"{k}-{view}", config=config, set=extra,
                progress=progress, models_dir=models_dir)
        runs.append((view, r, video))
    path, sets = _config(config, set)
    passes = [(view, os.fspath(video), os.fspath(r.dir)) for view, r, video in runs]
    _gait.visit(os.fspath(out), passes, path, sets, subject, session, date)
    return Visit(out, [r for _, r, _ in runs])
