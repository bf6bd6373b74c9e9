"""gait.run, gait.load, gait.kin and the Run they return."""

import json
import os
import pathlib
import tempfile

from gait import _gait
from gait._config import Config, as_sets
from gait._progress import progress_callback

# The per-run tables, by attribute, in the order of the run folder's files.
TABLES = (
    "angles",
    "events",
    "bouts",
    "cycles",
    "cycles_all",
    "cycle_quality",
    "spatiotemporal",
    # A front or back view's (None for a side view).
    "frontal_view",
    "frontal_angles",
    "frontal_cycles",
    "frontal_scalars",
    "frontal_feet",
)


class Run:
    """A run folder and its results as pandas DataFrames.

    The tables have the columns and order of the folder's CSV files
    (angles.csv, events.csv, ...). After gait.run they come from memory at
    full precision; gait.load reads the files (6 decimals).
    """

    def __init__(self, dir, data=None):
        self.dir = pathlib.Path(dir)
        self._data = data
        self._cache = {}

    def __repr__(self):
        return f"gait.Run({str(self.dir)!r})"

    @property
    def manifest(self):
        """run.json as a dict (None for gait.kin, which has no run)."""
        # The file, not the run's own summary: the report step adds to it.
        path = self.dir / "run.json"
        if path.is_file():
            return json.loads(path.read_text())
        text = None if self._data is None else self._data.get("manifest")
        return None if text is None else json.loads(text)

    @property
    def keypoints(self):
        """Keypoints in DeepLabCut's layout: columns (scorer, bodyparts, coords), index frame."""
        return self._table("keypoints", self._keypoints)

    def _keypoints(self):
        if self._data is not None:
            return keypoints_frame(self._data["keypoints"], self._data["scorer"])
        return read_dlc(self.dir / "keypoints.csv")

    @property
    def scores(self):
        """scores.csv of the report (None when the run wrote none)."""
        return self._table("scores", lambda: read_csv(self.dir / "scores.csv"))

    def _table(self, name, make):
        if name not in self._cache:
            self._cache[name] = make()
        return self._cache[name]

    def _kin_table(self, name):
        def make():
            tables = None if self._data is None else self._data.get("tables")
            if tables is not None:
                return columns_frame(tables[name]) if name in tables else None
            return read_csv(self.dir / f"{name}.csv")

        return self._table(name, make)


def _table_property(name):
    return property(lambda self: self._kin_table(name), doc=f"{name}.csv as a DataFrame.")


for _name in TABLES:
    setattr(Run, _name, _table_property(_name))


def run(input, out=None, config=None, set=None, progress=True, models_dir=None):
    """Runs the pipeline on a video, an image folder or an image, as `gait run`.

    out: the run folder (None: a new temporary folder). config: a pipeline
    TOML, a run.json to repeat, or a gait.Config. set: overrides, e.g.
    {"pose.backend": "ort"}. progress: a tqdm bar when tqdm is installed,
    else the terminal bar; False for none. Ctrl-C stops after the frame in
    flight and raises KeyboardInterrupt; the cache keeps the frames done.
    """
    path, sets = _config(config, set)
    if out is None:
        out = tempfile.mkdtemp(prefix="gait-run-")
    callback, terminal = progress_callback(progress)
    try:
        data = _gait.run(
            os.fspath(input),
            os.fspath(out),
            path,
            sets,
            None if models_dir is None else os.fspath(models_dir),
            terminal,
            callback,
        )
    finally:
        if callback is not None:
            callback.close()
    return Run(data["dir"], data)


def load(run_dir):
    """An earlier run, from its folder."""
    run_dir = pathlib.Path(run_dir)
    if not (run_dir / "keypoints.csv").is_file():
        raise _gait.InputError(f"{run_dir}: not a gait run folder (no keypoints.csv)")
    return Run(run_dir)


def kin(keypoints, fps, config=None, corrections=None, out=None, set=None):
    """Angles, events and cycles from a DeepLabCut-layout DataFrame, as `gait kin`.

    keypoints: columns (scorer, bodyparts, coords) with coords x, y,
    likelihood (a multi-animal file's individual level is taken first).
    corrections: a corrections.toml to apply. out: the folder the files go
    to (None: a new temporary folder).
    """
    names, frames, values = dlc_arrays(keypoints)
    path, sets = _config(config, set)
    if corrections is not None:
        sets.append(f"kinematics.corrections={json.dumps(os.fspath(corrections))}")
    if out is None:
        out = tempfile.mkdtemp(prefix="gait-kin-")
    data = _gait.kin(names, frames, values, float(fps), os.fspath(out), path, sets)
    return Run(data["dir"], data)


def _config(config, extra):
    if isinstance(config, Config):
        return config.path, config.sets + as_sets(extra)
    return (None if config is None else os.fspath(config)), as_sets(extra)


def dlc_arrays(df):
    """Names, frame numbers and flat x, y, likelihood values of a DeepLabCut table."""
    import numpy as np

    columns = df.columns
    if getattr(columns, "nlevels", 1) < 3:
        raise _gait.InputError(
            "keypoints: expected DeepLabCut columns (scorer, bodyparts, coords); "
            "read the CSV with pd.read_csv(path, header=[0, 1, 2], index_col=0)"
        )
    parts = columns.get_level_values(columns.nlevels - 2)
    coords = columns.get_level_values(columns.nlevels - 1)
    names = list(dict.fromkeys(parts))
    missing = [
        f"{n}/{c}"
        for n in names
        for c in ("x", "y", "likelihood")
        if not ((parts == n) & (coords == c)).any()
    ]
    if missing:
        raise _gait.InputError(f"keypoints: missing columns {', '.join(missing)}")
    order = [
        int(np.flatnonzero((parts == n) & (coords == c))[0])
        for n in names
        for c in ("x", "y", "likelihood")
    ]
    values = df.iloc[:, order].to_numpy(dtype="float64")
    frames = [int(f) for f in df.index]
    return names, frames, values.ravel().tolist()


def keypoints_frame(kp, scorer):
    """The DeepLabCut DataFrame of the native keypoints arrays."""
    import numpy as np
    import pandas as pd

    names = kp["names"]
    frames = np.frombuffer(kp["frames"], dtype="int64")
    values = np.frombuffer(kp["values"], dtype="float64").reshape(len(frames), 3 * len(names))
    columns = pd.MultiIndex.from_tuples(
        [(scorer, n, c) for n in names for c in ("x", "y", "likelihood")],
        names=["scorer", "bodyparts", "coords"],
    )
    return pd.DataFrame(values.copy(), index=pd.Index(frames.copy()), columns=columns)


def columns_frame(columns):
    """A DataFrame of native columns [(name, dtype, data)], as pandas reads the CSV."""
    import numpy as np
    import pandas as pd

    data = {}
    if not any(len(values) for _, _, values in columns):
        # read_csv types no column of a table without rows.
        return pd.DataFrame({name: pd.Series([], dtype=object) for name, _, _ in columns})
    for name, dtype, values in columns:
        if dtype == "object":
            # read_csv reads an empty cell as NaN.
            values = [v if v != "" else np.nan for v in values]
            if values and all(v is np.nan for v in values):
                values = np.full(len(values), np.nan)
            data[name] = values
        else:
            data[name] = np.frombuffer(values, dtype=dtype).copy()
    return pd.DataFrame(data)


def read_csv(path):
    import pandas as pd

    return pd.read_csv(path) if pathlib.Path(path).is_file() else None


def read_dlc(path):
    """A DeepLabCut CSV; its first three lines are the column levels.

    pd.read_csv(header=[0, 1, 2]) would take a first frame without any
    keypoint (a line of one number) for a line of index names.
    """
    import pandas as pd

    with open(path, newline="") as f:
        header = [next(f).rstrip("\r\n").split(",") for _ in range(3)]
    df = pd.read_csv(path, header=None, skiprows=3, index_col=0)
    df.index.name = None
    df.columns = pd.MultiIndex.from_arrays(
        [h[1:] for h in header], names=["scorer", "bodyparts", "coords"]
    )
    return df
