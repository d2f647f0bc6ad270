"""The region tracker's checks on drawn stereo frames (a parallel pinhole pair, no video)."""

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourSource
from wipelab.vision.region_tracker import RegionTracker

FOCAL, SIZE, BASELINE = 300.0, (320, 240), 0.1
ORANGE, SKIN = (20, 110, 240), (30, 120, 235)  # BGR: a vivid orange, a hand of a near hue


def _tracker() -> tuple[RegionTracker, np.ndarray]:
    """A tracker that has found a 10 cm sponge 1 m in front of the left camera."""
    K = np.array([[FOCAL, 0, SIZE[0] / 2], [0, FOCAL, SIZE[1] / 2], [0, 0, 1]])
    calibration = StereoCalibration(SIZE, K, np.zeros(5), K.copy(), np.zeros(5), np.eye(3),
                                    np.array([-BASELINE, 0.0, 0.0]))
    tracker = RegionTracker(calibration, ColourSource(name="orange"))
    point = np.array([0.0, 0.05, 1.0])
    tracker.size, tracker.model = 0.1, tracker.prior
    tracker.history.append((0, point))
    tracker.frame = 0
    return tracker, point


def _frames(point: np.ndarray, hand_in_right: bool) -> tuple[np.ndarray, np.ndarray]:
    """Grey frames with the sponge (30 x 20 px) at ``point``; the right one with a hand of
    the sponge's hue beside it, as large as the sponge, when ``hand_in_right``."""
    frames = []
    for camera, shift in (("left", 0.0), ("right", -BASELINE)):
        frame = np.full((SIZE[1], SIZE[0], 3), 128, np.uint8)
        u = int(round(FOCAL * (point[0] + shift) / point[2] + SIZE[0] / 2))
        v = int(round(FOCAL * point[1] / point[2] + SIZE[1] / 2))
        cv2.rectangle(frame, (u - 15, v - 10), (u + 14, v + 9), ORANGE, -1)
        if hand_in_right and camera == "right":
            cv2.rectangle(frame, (u - 15, v + 10), (u + 14, v + 29), SKIN, -1)
        frames.append(frame)
    return frames[0], frames[1]


def test_until_the_usual_area_is_known_both_cameras_regions_must_agree_in_size():
    """A region that takes in a hand of a near hue in one camera only is not valid while
    the tracker learns what is usual, and teaches it nothing: a first area twice the
    sponge's would make every later region of that camera look too small."""
    tracker, point = _tracker()
    estimate = tracker.step(*_frames(point, hand_in_right=True))
    assert not estimate.valid
    assert "another size" in estimate.reason
    assert not tracker.areas[0] and not tracker.areas[1]
    estimate = tracker.step(*_frames(point, hand_in_right=False))
    assert estimate.valid
    assert np.allclose(estimate.point, point, atol=0.01)
    assert len(tracker.areas[0]) == len(tracker.areas[1]) == 1
    assert np.allclose(tracker.areas[0][0], 30 * 20 / FOCAL ** 2, rtol=0.15)
