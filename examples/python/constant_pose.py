"""The smallest Python pose stage: the same keypoints in every frame.

It costs nothing itself, so it measures what handing frames to Python and
reading its keypoints back costs (tools/python/bench_stage.sh). Use:

    [pose]
    kind = "python"
    module = "constant_pose"      # with examples/python on PYTHONPATH
    class = "ConstantPose"
"""

import numpy as np


class ConstantPose:
    keypoints = "blazepose33"

    def __init__(self, options):
        x = float(options.get("x", 100.0))
        self._pose = np.tile([x, 200.0, 0.9], (33, 1))

    def estimate(self, frames):
        return [self._pose for _ in frames]
