"""gait.Config: a pipeline config file plus overrides, checked by gait itself."""

import json
import os

from gait import _gait


def toml_value(value):
    """A Python value as a TOML literal for `--set key=value`."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} as a config value")


def as_sets(values):
    """`set=` of gait.run (a dict, or a list of "table.key=value") as --set strings."""
    if values is None:
        return []
    if isinstance(values, dict):
        return [f"{k}={toml_value(v)}" for k, v in values.items()]
    return [str(v) for v in values]


class Config:
    """A pipeline config: a TOML file (or the built-in default) and overrides.

    Every change is checked at once by gait's own code, so a bad value raises
    gait.ConfigError with the message the `gait` command prints.
    """

    def __init__(self, path=None, sets=()):
        self.path = None if path is None else os.fspath(path)
        self.sets = list(sets)
        self.to_toml()

    @classmethod
    def load(cls, path=None):
        """The config in `path` (a pipeline TOML or a run's run.json); None: the default."""
        return cls(path)

    def set(self, key, value=None):
        """Overrides `key` ("table.key"), as `--set key=value`; returns the config.

        A dict sets several keys at once, checked together, e.g. a Python pose stage:
        cfg.set({"pose.kind": "python", "pose.module": "m", "pose.class": "C"}).
        """
        changes = key.items() if isinstance(key, dict) else [(key, value)]
        sets = self.sets + [f"{k}={toml_value(v)}" for k, v in changes]
        _gait.resolve_config(self.path, sets)
        self.sets = sets
        return self

    def to_toml(self):
        """The resolved config, every default filled in."""
        return _gait.resolve_config(self.path, self.sets)

    def __repr__(self):
        return f"gait.Config(path={self.path!r}, sets={self.sets!r})"
