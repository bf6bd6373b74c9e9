"""A pose stage that finds the same person in every frame: the smallest Python stage the tests run."""

import numpy as np

# 33 BlazePose landmarks of someone standing near the frame's centre (x, y in pixels, confidence).
POSE = np.array(
    [[880.0 + 3.0 * (i % 11), 300.0 + 12.0 * i, 0.9] for i in range(33)],
    dtype=np.float64,
)


class ConstantPose:
    keypoints = "blazepose33"

    def __init__(self, options):
        self.options = options
        self.pose = POSE.copy()
        if "shift_x" in options:
            self.pose[:, 0] += options["shift_x"]

    def estimate(self, frames):
        for frame in frames:
            assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
        return [self.pose for _ in frames]

    def reset(self):
        pass
