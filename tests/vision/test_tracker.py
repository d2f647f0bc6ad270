"""The sponge tracker on a short synthetic demonstration: region and box estimates,
occlusion, frames and colour sources, and the box refinement's scoring windows."""

from dataclasses import replace

import numpy as np
import pytest

from wipelab.stages.track import TrackParams, run_tracker
from wipelab.vision.box_tracker import _View
from wipelab.vision.calibration import load_calibration
from wipelab.vision.colour_model import ColourSource, vivid_part
from wipelab.vision.projection import invert_transform, transform_points
from wipelab.vision.sponge_box import SpongeBox
from wipelab.vision.region_tracker import RegionTrackerParams
from wipelab.vision.tracker import (SpongeTracker, TrackerParams, commonest_failure,
                                    fleeting_runs, still_runs)
from wipelab.vision.undistortion import pinhole
from wipelab.vision.video_io import StereoVideoReader


def _run(demo, calibration, colour=ColourSource(name="yellow"), sponge=None):
    """Two passes as the track stage runs them: (poses, valid, quality, tracker)."""
    tracker = SpongeTracker(calibration, colour, TrackerParams(seed=1, sponge=sponge))
    reader = StereoVideoReader(demo / "left.mp4", demo / "right.mp4")
    result = run_tracker(tracker, reader, TrackParams(), quiet=True)
    if result is None:
        n = reader.frame_count
        return np.full((n, 4), np.nan), np.zeros(n, bool), np.full(n, ""), tracker
    return result.poses, result.valid, result.quality, tracker


@pytest.fixture(scope="module")
def calibration(short_demo):
    return load_calibration(short_demo / "calibration.yaml")


@pytest.fixture(scope="module")
def region_only(short_demo, calibration):
    return _run(short_demo, calibration)


@pytest.fixture(scope="module")
def with_box(short_demo, calibration):
    return _run(short_demo, calibration, sponge=SpongeBox())


def _shape_and_bias(poses, valid, centre):
    error = poses[valid, :3] - centre[valid]
    bias = error.mean(axis=0)
    return np.sqrt(np.mean(np.sum((error - bias) ** 2, axis=1))), np.linalg.norm(bias)


def test_colour_region_alone_tracks_the_shape_of_the_movement(region_only, short_truth):
    poses, valid, quality, tracker = region_only
    t, centre, visible = short_truth
    assert valid[visible == 1].mean() > 0.97
    assert set(quality[valid]) == {"centroid"} and set(quality[~valid]) == {""}
    shape, bias = _shape_and_bias(poses, valid, centre)
    assert shape < 0.0025
    assert bias < 0.02  # the visible region's centre, not the box centre
    assert np.all(np.isfinite(poses[valid, 3]))  # yaw of the region's long axis
    assert 0.05 < tracker.region.size < 0.12


def test_a_known_sponge_size_gives_the_box_centre(with_box, short_truth):
    poses, valid, quality, tracker = with_box
    t, centre, visible = short_truth
    assert valid[visible == 1].mean() > 0.97
    assert (quality[valid] == "box").mean() > 0.9
    error = np.linalg.norm(poses[valid, :3] - centre[valid], axis=1)
    assert np.sqrt(np.mean(error ** 2)) < 0.004
    assert np.median(error) < 0.003
    # the box's outline is scored on the colour of all the sponge's faces, its shaded sides
    # too, not only on the vivid part the region's centre is measured on
    region = tracker.region
    for window, mask in zip(region.seed_windows, region.seed_masks):
        shaded = (mask > 0) & ~(vivid_part(window, mask) > 0)
        assert shaded.sum() > 100
        assert region.body_model.back_project(window)[shaded].mean() > 0.9


@pytest.mark.parametrize("run", ["region_only", "with_box"])
def test_full_occlusion_is_marked_invalid_and_tracking_recovers(run, request, short_truth):
    poses, valid, quality, _ = request.getfixturevalue(run)
    t, centre, visible = short_truth
    hidden = np.flatnonzero(visible == 0)
    assert len(hidden) > 5
    assert not valid[hidden].any()
    assert np.all(np.isnan(poses[hidden]))
    end = hidden[-1] + 1
    regained = end + np.flatnonzero(valid[end:])[0]
    assert t[regained] - t[end] <= 0.5


def test_without_a_world_pose_it_tracks_in_the_left_camera_frame(short_demo, calibration,
                                                                 short_truth):
    poses, valid, _, _ = _run(short_demo, replace(calibration, T_world_left=None))
    t, centre, visible = short_truth
    expected = transform_points(invert_transform(calibration.T_world_left), centre)
    assert valid[visible == 1].mean() > 0.9
    shape, _ = _shape_and_bias(poses, valid, expected)
    assert shape < 0.003


def test_a_colour_absent_from_the_video_is_never_found(short_demo, calibration):
    poses, valid, _, tracker = _run(short_demo, calibration, ColourSource(name="blue"))
    assert not valid.any() and np.all(np.isnan(poses))
    assert not tracker.identified


def test_colour_learnt_from_a_region_of_the_first_frame(short_demo, calibration, short_truth):
    t, centre, visible = short_truth
    centre_left = transform_points(invert_transform(calibration.T_world_left), centre[0])
    u, v = calibration.left.project(centre_left[None])[0].astype(int)
    # a region on the visible front of the sponge (the hand hides the middle of its top)
    poses, valid, _, _ = _run(short_demo, calibration, ColourSource(roi=(u - 25, v + 6, 50, 12)))
    assert valid[visible == 1].mean() > 0.9
    shape, _ = _shape_and_bias(poses, valid, centre)
    assert shape < 0.003


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


def test_scoring_windows_hold_every_sample_of_every_pose_with_the_margin(short_demo, with_box,
                                                                         short_truth):
    tracker = with_box[3]
    box = tracker.box
    frames = next(iter(StereoVideoReader(short_demo / "left.mp4", short_demo / "right.mp4")))
    _, centre, _ = short_truth
    rng = np.random.default_rng(3)
    poses = np.column_stack([centre[0] + rng.normal(size=(50, 3)) * 0.01,
                             rng.uniform(-1.5, 1.5, 50)])
    windows = box._windows(frames, poses)
    margin = box.params.window_margin
    offsets = box.params.search_offsets + box.params.refine_offsets
    for pose in poses:
        for samples, window, view in zip(box._samples(box.coarse, pose, offsets),
                                         windows, box.views):
            c, s = np.cos(pose[3]), np.sin(pose[3])
            camera = (view.R @ pose[:3] + view.t) + c * samples.MA + s * samples.MB + samples.MC
            uv = pinhole(camera, view.K) - window.feature.origin
            height, width = window.feature.probability.shape
            assert uv.min() >= margin - 1
            assert np.all(uv < [width - margin + 1, height - margin + 1])


def test_yaw_before_any_plane_is_measured_in_the_tracking_frame(calibration):
    """A region measured before the table or the sponge's plane is known (an untextured table,
    the first frames) gets a yaw about the tracking frame's own z axis, not an error."""
    tracker = SpongeTracker(calibration, ColourSource(name="yellow"))
    assert tracker.region.sponge_plane() is None
    along_x_of_track = tracker.T_left_track[:3, :3] @ np.array([1.0, 0.0, 0.0])
    along_y_of_track = tracker.T_left_track[:3, :3] @ np.array([0.0, 1.0, 0.0])
    assert tracker._yaw(along_x_of_track) == pytest.approx(0.0, abs=1e-9)
    assert abs(tracker._yaw(along_y_of_track)) == pytest.approx(np.pi / 2, abs=1e-9)


def test_valid_runs_of_at_most_a_fifth_of_a_second_between_losses_are_fleeting():
    """At 30 fps, runs of up to 6 valid frames are fleeting, 7 are the sponge found again;
    a short run that the video's end cuts off is kept, one at its start is not."""
    runs = [(0, 3), (10, 6), (20, 7), (40, 1), (50, 20), (95, 5)]   # (start, length)
    valid = np.zeros(100, bool)
    for start, length in runs:
        valid[start:start + length] = True
    fleeting = fleeting_runs(valid, fps=30.0)
    expected = np.zeros(100, bool)
    for start, length in [(0, 3), (10, 6), (40, 1)]:
        expected[start:start + length] = True
    assert np.array_equal(fleeting, expected)
    assert fleeting_runs(valid, fps=60.0)[20:27].all()   # 7 frames at 60 fps: 0.12 s
    assert not fleeting_runs(np.ones(5, bool), fps=30.0).any()


def test_runs_that_keep_still_after_the_sponge_moved_are_still_things_not_the_sponge():
    """A 0.08 m sponge: a run after the first moving one whose points keep within 2 cm (a
    quarter of its size) is a still thing, however short or long; a still run before it is
    the sponge resting where it started; pieces of one run split by a short gap are judged
    together."""
    n = 240
    valid = np.zeros(n, bool)
    points = np.zeros((n, 3))
    t = np.arange(n) / 30.0
    circle = np.stack([0.1 * np.cos(2 * np.pi * t), 0.1 * np.sin(2 * np.pi * t),
                       np.full(n, 0.6)], axis=1)
    rest, patch = np.array([0.1, 0.0, 0.6]), np.array([-0.3, 0.2, 0.6])
    jitter = 0.004 * np.sin(np.arange(n))[:, None]
    for start, end, where in [(0, 10, rest), (20, 60, circle), (80, 87, patch),
                              (100, 108, patch), (110, 130, circle), (150, 240, patch)]:
        valid[start:end] = True
        points[start:end] = (where[start:end] if where.ndim == 2 else where) + jitter[start:end]
    still = still_runs(valid, points, 0.08, RegionTrackerParams())
    expected = np.zeros(n, bool)
    expected[80:87] = expected[150:240] = True
    assert np.array_equal(still, expected)
    # with points spread a little wider than a quarter of the sponge, the patch moved
    spread = points.copy()
    spread[80:87, 0] += np.linspace(-0.05, 0.05, 7)
    assert not still_runs(valid, spread, 0.08, RegionTrackerParams())[80:87].any()


def test_the_commonest_failure_is_named_in_a_users_terms():
    """The reasons of frames that were not valid, counted by kind: the region tracker's
    wording (with its numbers) becomes what a user can act on."""
    reasons = ["left region 1.71x its usual area; right region 2.30x its usual area",
               "right region 0.62x its usual area", "the cameras' regions disagree",
               "searching", "left region 1.40x its usual area"]
    kind, share = commonest_failure(reasons)
    assert kind.startswith("the sponge's colour region kept changing size")
    assert share == pytest.approx(0.6)
    assert commonest_failure(["searching for the moving sponge", "left region not seen; "
                              "right region not seen"]) == ("it was lost and not found again",
                                                            1.0)
    assert commonest_failure(["at the edge of the image"])[0] == \
        "its colour region failed the tracker's checks"
    assert commonest_failure([]) == ("", 0.0)
