"""The region tracker's checks on drawn stereo frames (a parallel pinhole pair, no video)."""

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourSource
from wipelab.vision.region_tracker import RegionTracker
from wipelab.vision.table_plane import Plane

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
    tracker._table_centre = point.copy()
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


def _followed(tracker: RegionTracker, points) -> None:
    """Make ``tracker`` have followed ``points`` (n, 3), one per frame, as valid."""
    for frame, point in enumerate(points):
        tracker._valid_points.append((frame, np.asarray(point, float)))
    tracker.frame = len(points)


def test_a_big_thing_whose_centre_an_arm_moves_by_a_little_of_its_size_is_still():
    # a 20 cm cloth that the wiping arm covers here and there: its region's centre moves
    # periodically by 2.5 cm, a wiping sponge's by its stroke (10 cm or more)
    t = np.arange(100) / 30.0
    wobble = 0.025 * np.stack([np.sin(2 * np.pi * t), np.zeros_like(t), np.zeros_like(t)], 1)
    cloth, _ = _tracker()
    cloth.size = 0.2
    _followed(cloth, np.array([0.0, 0.05, 1.0]) + wobble)
    assert cloth._kept_still(np.array([0.0, 0.05, 1.0]))
    sponge, _ = _tracker()  # 10 cm, wiping a 10 cm stroke
    _followed(sponge, np.array([0.0, 0.05, 1.0]) + 2.0 * wobble)
    assert not sponge._kept_still(np.array([0.0, 0.05, 1.0]))


def test_after_following_a_still_thing_the_sponge_is_identified_anew():
    tracker, point = _tracker()
    tracker._track_start = 5
    _followed(tracker, np.repeat(point[None], 100, axis=0))
    tracker._forget_track(point)
    assert not tracker.identified  # its size was the still thing's
    assert tracker.still_tracks == [(5, 100)]
    assert tracker.candidates.is_static(point, 0.1)
    assert not any(background.ghosts.any() for background in tracker.backgrounds)


def test_a_still_thing_found_after_the_sponge_wiped_is_forgotten_but_not_the_sponge():
    """Tracked wiping for 100 frames, then lost and "found" as a cup that stayed put for
    100 frames: the cup's frames are a still track and the cup a still thing, but the
    sponge (its size, the plane it moves in, where it wiped) is still known and searched
    for from the next frame."""
    tracker, point = _tracker()
    t = np.arange(100) / 30.0
    wiping = point + 0.1 * np.stack([np.sin(2 * np.pi * t), np.zeros_like(t),
                                     np.zeros_like(t)], 1)
    cup = point + np.array([0.3, 0.0, 0.0])
    _followed(tracker, np.concatenate([wiping, np.repeat(cup[None], 100, axis=0)]))
    tracker._stereo_points.extend((f, q) for f, q in tracker._valid_points)
    tracker._track_start = 100
    tracker._forget_track(cup)
    assert tracker.identified and tracker.size == 0.1
    assert tracker.still_tracks == [(100, 200)]
    assert tracker.candidates.is_static(cup, 0.1)
    assert [f for f, _ in tracker._valid_points] == list(range(100))
    assert max(f for f, _ in tracker._stereo_points) == 99
    assert tracker.failures > tracker.params.coast_frames and not tracker.history


def test_the_plane_the_sponge_moves_in_lies_on_the_table_whatever_its_first_stereo_points():
    """The first stereo points after the sponge is found can be centimetres off (a hand
    hides its region differently in the two views): the plane of the sponge's point stays
    between just under the table and a hand-held sponge's height above it."""
    tracker, _ = _tracker()
    tracker.table = Plane(np.array([0.0, -1.0, 0.0]), -0.1)  # 10 cm under the cameras' axis
    for depth_below, expected in ((0.06, -0.03), (-0.12, 0.08), (0.02, -0.02)):
        tracker._stereo_points.clear()
        tracker._stereo_points.extend([(0, np.array([0.0, 0.1 + depth_below, 1.0]))] * 3)
        tracker._refresh_plane(force=True)
        height = tracker.sponge_plane().offset - tracker.table.offset
        assert abs(height - expected) < 1e-9, (depth_below, height)


def test_a_still_thing_found_again_after_a_short_loss_was_followed_since_it_showed_still():
    """Lost for a few frames and found again, the still thing's track is one track: all of
    the frames that showed it still are dropped, not only those since it was found again."""
    tracker, point = _tracker()
    tracker._track_start = 80  # found again 20 frames before it is known to be still
    _followed(tracker, np.repeat(point[None], 100, axis=0))
    tracker._forget_track(point)
    window = round(tracker.params.still_seconds * tracker.params.acquisition.fps)
    assert tracker.still_tracks == [(100 - window + 1, 100)]


def test_a_sponge_that_rested_then_wiped_slowly_is_identified_whole():
    """The sponge rests for 3 s, then wipes a stroke smaller than itself: while it rested it
    became a still thing of its colour (a ghost) that no point of the moving candidate's
    path has at its middle; the ghost lies where the path went, so it is forgotten, and the
    sponge's whole region (not what is left beside the ghost) gives its size."""
    calibration = _tracker()[0].calibration
    tracker = RegionTracker(calibration, ColourSource(name="orange"))
    rest = np.array([0.0, 0.05, 1.0])
    frame = 0
    for frame in range(400):
        t = max(0, frame - 90) / 30.0
        tracker.step(*_frames(rest + [0.03 * (1 - np.cos(2 * np.pi * 0.7 * t)), 0, 0], False))
        if tracker.identified:
            break
    assert tracker.identified and frame > 90
    assert abs(tracker.size / (np.sqrt(30 * 20) / FOCAL) - 1) < 0.15
    for later in range(frame + 1, frame + 31):
        t = (later - 90) / 30.0
        estimate = tracker.step(*_frames(
            rest + [0.03 * (1 - np.cos(2 * np.pi * 0.7 * t)), 0, 0], False))
        assert estimate.valid, (later, estimate.reason)
