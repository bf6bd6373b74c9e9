"""gait: markerless gait analysis of lower-limb prosthetic users, from Python.

    import gait
    run = gait.run("walk.mp4", out="runs/walk")
    run.angles          # pandas DataFrame, as angles.csv
    run.cycles          # mean curves over the gait cycle
    gait.load("runs/walk").events

The pipeline is gait's own (the same code as the `gait` command), so a run
from Python and from the command line give the same files. Stages can be
written in Python (`kind = "python"` in a config; see docs/adding-a-stage.md).
"""

from gait._gait import (
    ConfigError,
    GaitError,
    InputError,
    OutputError,
    StageError,
    __version__,
)
from gait._config import Config
from gait._run import Run, kin, load, run
from gait._visit import Visit, visit, visit_runs

__all__ = [
    "Config",
    "ConfigError",
    "GaitError",
    "InputError",
    "OutputError",
    "Run",
    "StageError",
    "Visit",
    "__version__",
    "kin",
    "load",
    "run",
    "visit",
    "visit_runs",
]
