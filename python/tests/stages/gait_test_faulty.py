"""Pose stages that break the protocol, one way each; every one must stop the run with one line."""

import numpy as np

GOOD = np.tile(np.array([[880.0, 500.0, 0.9]]), (33, 1))


class Base:
    keypoints = "blazepose33"

    def __init__(self, options):
        pass


class WrongShape(Base):
    def estimate(self, frames):
        return [np.zeros((17, 3)) for _ in frames]


class IntDtype(Base):
    def estimate(self, frames):
        return [np.zeros((33, 3), dtype=np.int64) for _ in frames]


class NaNPose(Base):
    def estimate(self, frames):
        pose = GOOD.copy()
        pose[25, 1] = np.nan
        return [pose for _ in frames]


class Raises(Base):
    def estimate(self, frames):
        raise RuntimeError("the model is on fire")


class WrongCount(Base):
    def estimate(self, frames):
        return [GOOD for _ in frames[1:]]


class KeepsFrame(Base):
    def estimate(self, frames):
        self.kept = frames[0]
        return [GOOD for _ in frames]


class NoMethod(Base):
    pass


class BadLayout(Base):
    keypoints = "halpe26"

    def estimate(self, frames):
        return [GOOD for _ in frames]


class RaisesInInit:
    keypoints = "blazepose33"

    def __init__(self, options):
        raise ValueError("no weights")

    def estimate(self, frames):
        return [GOOD for _ in frames]


class LateBadItem(Base):
    """Good for two batches, then one wrong item: the error names that item's frame."""

    def __init__(self, options):
        self.calls = 0

    def estimate(self, frames):
        self.calls += 1
        poses = [GOOD for _ in frames]
        if self.calls == 3:
            poses[2] = np.zeros((33, 2))
        return poses


class LateRaise(Base):
    """Raises in its second call: the error names the call's first frame."""

    def __init__(self, options):
        self.calls = 0

    def estimate(self, frames):
        self.calls += 1
        if self.calls == 2:
            raise KeyError("lost")
        return [GOOD for _ in frames]
