"""mediapipe's own BlazePose (Python, ``mediapipe==0.10.14``) as a gait pose stage.

The same model as gait's built-in ``kind = "blazepose"`` (BlazePose "full", the files of the same wheel), run
by mediapipe itself, so a run with it checks the built-in against the reference implementation, or serves as a
template for wrapping any Python pose model. Use (``configs/python-mediapipe.toml``)::

    [pose]
    kind = "python"
    module = "mediapipe_pose"        # this file: put examples/python on PYTHONPATH
    class = "MediapipePose"
    [pose.options]                   # all optional; the defaults match the built-in BlazePose
    static_image_mode = false        # false: video mode, each frame's crop from the previous frame's
                                     # landmarks (as the built-in tracks); true: detect in every frame
    smooth_landmarks = false         # mediapipe's One-Euro landmark filter (video mode only); the built-in
                                     # does not smooth (gait's [postprocess] filters later)
    min_detection_confidence = 0.5   # person detector score threshold
    min_tracking_confidence = 0.5    # pose presence needed to keep tracking (else detect again)
    model_complexity = 1             # 1 = "full" (in the wheel); 0 "lite" and 2 "heavy" are downloaded
                                     # by mediapipe on first use (network needed)

with mediapipe in the active virtual environment (``tools/python/setup.sh`` makes one)::

    source target/python-venv/bin/activate
    PYTHONPATH=examples/python gait run --config configs/python-mediapipe.toml --input walk.mp4 --out runs/mp

or from the ``gait`` package: ``gait.run("walk.mp4", config="configs/python-mediapipe.toml")`` with
``examples/python`` on ``sys.path``.

Keypoints: the 33 landmarks in mediapipe's order (``keypoints = "blazepose33"``), x and y in frame pixels with
the centre of the top-left pixel at (0, 0) (``x = nx * width - 0.5``, as the built-in), confidence = mediapipe's
visibility. A frame where mediapipe finds nobody gives ``None``.

Differences from the built-in: mediapipe picks the person itself (its detector's best one, then tracks it), so
it cannot follow gait's subject pass (``[subject]``, ``pose.person``); in a video with several people it may
follow someone else than the walker gait would choose (on the sample video it tracks the man on the box from
frame 3 to 169; ``--set input.first_frame=59`` starts it on the walker). In video mode mediapipe always smooths
the two auxiliary landmarks its next crop is built from (a One-Euro filter, even with
``smooth_landmarks = false``), the built-in does not, so the crops differ slightly and the keypoints by a few
pixels (sample, walker, frames 59-192: lower-limb median 2.8 px); with ``static_image_mode = true`` against
the built-in with ``pose.tracking = false`` (same detections, same crops) they agree to 0.02 px.

Frames: gait hands read-only, C-contiguous RGB ``uint8`` arrays that view its memory. mediapipe takes a
read-only C-contiguous array by reference (no copy) and keeps no reference after ``process`` returns (checked:
the array's reference count is unchanged), so the frames are passed as they are. An array that is not
C-contiguous (never from gait) is copied first, since mediapipe's reference mode refuses it.
"""

import numpy as np
import mediapipe as mp

_DEFAULTS = {
    "static_image_mode": False,
    "smooth_landmarks": False,
    "min_detection_confidence": 0.5,
    "min_tracking_confidence": 0.5,
    "model_complexity": 1,
}


class MediapipePose:
    """A gait pose stage running ``mp.solutions.pose.Pose`` frame by frame."""

    keypoints = "blazepose33"

    def __init__(self, options=None):
        options = dict(options or {})
        unknown = sorted(set(options) - set(_DEFAULTS))
        if unknown:
            raise ValueError(
                f"unknown option(s) {', '.join(unknown)}; known: {', '.join(sorted(_DEFAULTS))}"
            )
        self._options = {**_DEFAULTS, **options}
        self._pose = None
        self.reset()

    def _make(self):
        o = self._options
        return mp.solutions.pose.Pose(
            static_image_mode=bool(o["static_image_mode"]),
            model_complexity=int(o["model_complexity"]),
            smooth_landmarks=bool(o["smooth_landmarks"]),
            enable_segmentation=False,
            min_detection_confidence=float(o["min_detection_confidence"]),
            min_tracking_confidence=float(o["min_tracking_confidence"]),
        )

    def reset(self):
        """Forgets the person tracked (a new mediapipe graph)."""
        self.close()
        self._pose = self._make()

    def close(self):
        if self._pose is not None:
            self._pose.close()
            self._pose = None

    def estimate(self, frames):
        return [self._estimate_one(f) for f in frames]

    def _estimate_one(self, frame):
        if not frame.flags.c_contiguous:
            frame = np.ascontiguousarray(frame)
        height, width = frame.shape[:2]
        result = self._pose.process(frame)
        if result.pose_landmarks is None:
            return None
        out = np.array(
            [(l.x, l.y, l.visibility) for l in result.pose_landmarks.landmark], dtype=np.float64
        )
        out[:, 0] = out[:, 0] * width - 0.5
        out[:, 1] = out[:, 1] * height - 0.5
        return out
