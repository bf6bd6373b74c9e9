"""A stage module that cannot be imported."""

import gait_test_no_such_module  # noqa: F401


class Whatever:
    keypoints = "blazepose33"

    def estimate(self, frames):
        return [None for _ in frames]
