"""The table plane from dense stereo (wipelab.vision.table_stereo) on a small scene of the
independent generator: its height and tilt against the scene's own table, and a point too
near the cameras for any match (a hand in front of the lens) gives no points, not an error."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.stereo_scenes import render_scene
from wipelab.stages.track import open_demo
from wipelab.trajectory_csv import read_trajectory
from wipelab.vision.projection import invert_transform, transform_points
from wipelab.vision.table_stereo import TableStereo, ransac_plane

SEED = 5  # a development seed: H.264, wood-like table texture


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = render_scene(tmp_path_factory.mktemp("table") / "scene", SEED, duration=1.0,
                        small=True)
    plan = json.loads((path / "scene.json").read_text())
    demo = open_demo(path)
    left, right = next(iter(demo.reader))
    T_left_world = invert_transform(np.array(plan["cameras"]["T_world_left"]))
    truth = read_trajectory(path / "truth.csv", required=("t", "x", "y", "z"))
    sponge = transform_points(T_left_world, truth.array(["x", "y", "z"])[:1])[0]
    return demo.calibration, (left, right), sponge, T_left_world, plan["table"]["height"]


def test_the_table_plane_near_the_sponge_is_the_scenes_table(scene):
    calibration, frames, sponge, T_left_world, height = scene
    plane = TableStereo(calibration).plane_near([frames], sponge, radius=0.3)
    assert plane is not None
    up = T_left_world[:3, :3] @ np.array([0.0, 0.0, 1.0])   # the world's up, left frame
    assert np.degrees(np.arccos(abs(plane.normal @ up))) < 2.0
    # a point of the table top (world z = height) lies on the fitted plane
    on_top = transform_points(T_left_world, np.array([[0.8, 0.0, height]]))[0]
    assert abs(plane.distance(on_top[None])[0]) < 0.01


def test_a_point_too_near_the_cameras_gives_no_points(scene):
    calibration, frames, _, _, _ = scene
    points = TableStereo(calibration).table_points(*frames, np.array([0.0, 0.0, 0.02]))
    assert points.shape == (0, 3)


def test_with_the_worlds_up_axis_a_wall_larger_than_the_table_is_not_the_table():
    # a camera low over the table sees more of the wall behind it: the dominant plane of
    # the points is the wall, but only planes near level count when the up axis is known
    rng = np.random.default_rng(0)
    table = np.column_stack([rng.uniform(-0.3, 0.3, 800), rng.uniform(-0.3, 0.3, 800),
                             np.zeros(800)])
    wall = np.column_stack([rng.uniform(-0.5, 0.5, 3000), np.full(3000, 0.4),
                            rng.uniform(0.0, 0.6, 3000)])
    points = np.concatenate([table, wall]) + [0.0, 0.0, 1.0]
    up = np.array([0.0, 0.0, 1.0])
    assert abs(ransac_plane(points, 0.004, np.random.default_rng(1))[:800].mean()) < 0.5
    level = ransac_plane(points, 0.004, np.random.default_rng(1), towards=up)
    assert level[:800].all() and level[800:].mean() < 0.01  # (where the wall meets it)


def test_a_pool_of_pairs_gives_the_plane_of_their_points_concatenated(scene):
    # a pool grows by a frame pair at a time and each pair's points near the centre are
    # kept: the plane must be the very one of all the points at once (thinned evenly over
    # the pool, more points than a plane is fitted to)
    calibration, _, _, _, _ = scene
    rng = np.random.default_rng(3)
    pairs = []
    for count in (30000, 0, 24000, 12000):
        xy = rng.uniform(-0.6, 0.6, (count, 2))
        pairs.append(np.column_stack([xy, 1.0 + 0.1 * xy[:, 0] + rng.normal(0, 0.002, count)]))
    near, up = np.array([0.0, 0.0, 1.0]), np.array([0.1, 0.0, -1.0]) / np.hypot(0.1, 1.0)
    stereo = TableStereo(calibration)
    for k in range(1, len(pairs) + 1):
        pooled = stereo.plane_of_pairs(pairs[:k], near, 0.5, prior_normal=up)
        alone = TableStereo(calibration).plane_of_points(np.concatenate(pairs[:k]), near, 0.5,
                                                         prior_normal=up)
        assert (pooled.normal.tobytes(), pooled.offset, pooled.count) == \
            (alone.normal.tobytes(), alone.offset, alone.count)
    # the same arrays about another centre are filtered afresh
    moved = stereo.plane_of_pairs(pairs, near + [0.5, 0.0, 0.05], 0.2, prior_normal=up)
    assert moved.count < pooled.count
