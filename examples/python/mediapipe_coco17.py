"""A top-down COCO-17 pose stage: mediapipe's BlazePose (``mediapipe==0.10.14``) on the subject's box,
its landmarks written as the 17 COCO keypoints (no heels, no toes).

It stands for the top-down COCO-17 models researchers plug in (RTMPose, ViTPose, HRNet): they find the
keypoints of one person in a crop that a detector gives them. Here the crop is the subject's box that gait's
subject pass hands over (``estimate(self, frames, boxes)``), so the stage follows the walker gait chose, and
its keypoints have the layout such models give, so gait takes the events from the ankles. Use::

    [pose]
    kind = "python"
    module = "mediapipe_coco17"      # this file: put examples/python on PYTHONPATH
    class = "MediapipeCoco17"
    [pose.options]
    margin = 1.25                    # the crop's side over the box's side

``boxes[i]`` is ``None`` where the subject is not in view (the frame gets no pose) or a dict in frame pixels
with ``x0, y0, x1, y1`` (the square around the whole body), ``centre``, ``size`` and ``score``. Each crop runs
mediapipe in static-image mode (each crop is a new image: no tracking between crops).
"""

import mediapipe as mp
import numpy as np

# BlazePose landmark index of each COCO-17 keypoint, in COCO's order: nose, eyes, ears, shoulders, elbows,
# wrists, hips, knees, ankles (left before right).
_COCO_FROM_BLAZEPOSE = [0, 2, 5, 7, 8, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]


class MediapipeCoco17:
    """mediapipe's pose model on the subject's box, as a COCO-17 model."""

    keypoints = "coco17"

    def __init__(self, options=None):
        options = dict(options or {})
        self._margin = float(options.pop("margin", 1.25))
        if options:
            raise ValueError(f"unknown option(s) {', '.join(sorted(options))}; known: margin")
        self._pose = mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1)

    def estimate(self, frames, boxes):
        return [self._one(frame, box) for frame, box in zip(frames, boxes)]

    def _one(self, frame, box):
        if box is None:
            return None
        h, w = frame.shape[:2]
        cx, cy = box["centre"]
        half = 0.5 * self._margin * box["size"]
        x0, y0 = int(max(0, np.floor(cx - half))), int(max(0, np.floor(cy - half)))
        x1, y1 = int(min(w, np.ceil(cx + half))), int(min(h, np.ceil(cy + half)))
        if x1 - x0 < 8 or y1 - y0 < 8:
            return None
        crop = np.ascontiguousarray(frame[y0:y1, x0:x1])
        found = self._pose.process(crop).pose_landmarks
        if found is None:
            return None
        lm = found.landmark
        cw, ch = x1 - x0, y1 - y0
        # Normalised crop coordinates to frame pixels (pixel centres at integers, as gait's).
        return np.array(
            [[x0 + lm[i].x * cw - 0.5, y0 + lm[i].y * ch - 0.5, lm[i].visibility] for i in _COCO_FROM_BLAZEPOSE],
            dtype=np.float64,
        )

    def reset(self):
        pass
