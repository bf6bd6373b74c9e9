"""An edge stage and a regenerator written in Python that change nothing the pose model sees."""

import numpy as np


class GrayEdges:
    """The frame's green channel as the "edge map" (a uint8 image of the frame's size)."""

    def __init__(self, options):
        self.calls = 0

    def detect(self, frames):
        self.calls += 1
        return [np.ascontiguousarray(frame[:, :, 1]) for frame in frames]


class Identity:
    """Hands every frame back unchanged; checks the edge maps it is given."""

    def __init__(self, options):
        self.want_edges = options.get("want_edges", False)

    def regenerate(self, frames, edges):
        if self.want_edges:
            assert edges is not None and len(edges) == len(frames), "no edge maps"
            for frame, edge in zip(frames, edges):
                assert edge.dtype == np.uint8 and edge.shape == frame.shape[:2]
                assert np.array_equal(edge, frame[:, :, 1]), "edge map is not the green channel"
        for frame in frames:
            assert not frame.flags.writeable, "frames must be read-only"
        return [frame.copy() for frame in frames]
