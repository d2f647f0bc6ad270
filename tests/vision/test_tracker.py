from dataclasses import replace

import numpy as np
import pytest

from wipelab.vision.calibration import load_calibration
from wipelab.vision.colour_model import ColourSource
from wipelab.vision.projection import invert_transform, transform_points
from wipelab.vision.tracker import SpongeTracker, TrackerParams, _View
from wipelab.vision.undistortion import pinhole
from wipelab.vision.video_io import StereoVideoReader


def _run(demo, calibration, colour=ColourSource(name="yellow")):
    tracker = SpongeTracker(calibration, colour, TrackerParams(seed=1))
    estimates = [tracker.step(left, right)
                 for left, right in StereoVideoReader(demo / "left.mp4", demo / "right.mp4")]
    return (np.array([e.pose for e in estimates]), np.array([e.valid for e in estimates]),
            estimates)


@pytest.fixture(scope="module")
def tracked(short_demo):
    return _run(short_demo, load_calibration(short_demo / "calibration.yaml"))


def test_converges_to_the_sponge_centre_within_a_few_millimetres(tracked, short_truth):
    poses, valid, _ = tracked
    t, centre, visible = short_truth
    seen = visible == 1
    assert valid[seen].mean() > 0.97
    error = np.linalg.norm(poses[valid, :3] - centre[valid], axis=1)
    assert np.sqrt(np.mean(error ** 2)) < 0.004
    assert np.median(error) < 0.003


def test_full_occlusion_is_marked_invalid_and_tracking_recovers(tracked, short_truth):
    poses, valid, estimates = tracked
    t, centre, visible = short_truth
    hidden = np.flatnonzero(visible == 0)
    assert not valid[hidden].any()
    assert np.all(np.isnan(poses[hidden]))
    end = hidden[-1] + 1
    regained = end + np.flatnonzero(valid[end:])[0]
    assert t[regained] - t[end] <= 0.5
    after = valid & (np.arange(len(t)) >= regained)
    assert np.linalg.norm(poses[after, :3] - centre[after], axis=1).max() < 0.015
    assert estimates[hidden[0]].particles.shape == (TrackerParams().particles, 4)


def test_without_a_world_pose_it_tracks_in_the_left_camera_frame(short_demo, short_truth):
    calibration = load_calibration(short_demo / "calibration.yaml")
    poses, valid, _ = _run(short_demo, replace(calibration, T_world_left=None))
    t, centre, visible = short_truth
    expected = transform_points(invert_transform(calibration.T_world_left), centre)
    error = np.linalg.norm(poses[valid, :3] - expected[valid], axis=1)
    assert valid[visible == 1].mean() > 0.9
    assert np.median(error) < 0.006


def test_a_colour_absent_from_the_video_is_never_found(short_demo):
    poses, valid, _ = _run(short_demo, load_calibration(short_demo / "calibration.yaml"),
                           ColourSource(name="blue"))
    assert not valid.any() and np.all(np.isnan(poses))


def test_colour_learnt_from_a_region_of_the_first_frame(short_demo, short_truth):
    calibration = load_calibration(short_demo / "calibration.yaml")
    t, centre, visible = short_truth
    centre_left = transform_points(invert_transform(calibration.T_world_left), centre[0])
    u, v = calibration.left.project(centre_left[None])[0].astype(int)
    # a region on the visible front of the sponge (the hand hides the middle of its top)
    poses, valid, _ = _run(short_demo, calibration, ColourSource(roi=(u - 25, v + 6, 50, 12)))
    error = np.linalg.norm(poses[valid, :3] - centre[valid], axis=1)
    assert valid[visible == 1].mean() > 0.9
    assert np.median(error) < 0.004


def test_a_window_holds_the_projected_points_with_its_margin():
    K = np.array([[530.0, 0.0, 320.0], [0.0, 530.0, 240.0], [0.0, 0.0, 1.0]])
    view = _View(K, np.zeros(5), np.eye(4), (640, 480))
    width, height = view.undistorter.size
    points = np.array([[0.01, -0.02, 0.6], [-0.05, 0.03, 0.7], [0.04, 0.05, 0.5]])
    pixels = pinhole(points, view.K)
    assert view.window_around(points, 16) == (
        int(np.floor(pixels[:, 0].min())) - 16, int(np.floor(pixels[:, 1].min())) - 16,
        int(np.ceil(pixels[:, 0].max())) + 16, int(np.ceil(pixels[:, 1].max())) + 16)
    # clipped to the canvas, and the whole canvas once a point lies behind the camera
    assert view.window_around(np.array([[-1.0, -1.0, 0.5], [1.0, 1.0, 0.5]]), 16) == (
        0, 0, width, height)
    assert view.window_around(np.vstack([points, [[0.0, 0.0, -0.1]]]), 16) == (
        0, 0, width, height)


def test_scoring_windows_hold_every_sample_of_every_pose_with_the_margin(short_demo,
                                                                         short_truth):
    calibration = load_calibration(short_demo / "calibration.yaml")
    tracker = SpongeTracker(calibration, ColourSource(name="yellow"), TrackerParams(seed=1))
    frames = next(iter(StereoVideoReader(short_demo / "left.mp4", short_demo / "right.mp4")))
    assert tracker._learn_colour(frames)
    tracker.R_track_table = np.eye(3)  # the calibration has a world frame: z is up
    _, centre, _ = short_truth
    rng = np.random.default_rng(3)
    poses = np.column_stack([centre[0] + rng.normal(size=(50, 3)) * 0.01,
                             rng.uniform(-1.5, 1.5, 50)])
    windows = tracker._windows(frames, poses)
    margin = tracker.params.window_margin
    offsets = tracker.params.search_offsets + tracker.params.refine_offsets
    for pose in poses:
        for samples, window, view in zip(tracker._samples(tracker.coarse, pose, offsets),
                                         windows, tracker.views):
            c, s = np.cos(pose[3]), np.sin(pose[3])
            camera = (view.R @ pose[:3] + view.t) + c * samples.MA + s * samples.MB + samples.MC
            uv = pinhole(camera, view.K) - window.feature.origin
            height, width = window.feature.probability.shape
            assert uv.min() >= margin - 1
            assert np.all(uv < [width - margin + 1, height - margin + 1])
