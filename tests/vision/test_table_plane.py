"""The table plane: robust fit (with and without a prior normal) and points on the plane."""

from __future__ import annotations

import numpy as np
import pytest

from wipelab.vision.table_plane import Plane, fit_plane, points_on_plane


def _tilted_plane_points(rng, n, normal, offset, noise, outliers=0):
    plane = Plane(normal / np.linalg.norm(normal), offset)
    origin, e1, e2 = plane.basis()
    ab = rng.uniform(-0.2, 0.2, size=(n, 2))
    points = origin + ab[:, :1] * e1 + ab[:, 1:] * e2 + rng.normal(size=(n, 1)) * noise \
        * plane.normal
    if outliers:
        points[:outliers] += rng.uniform(0.05, 0.2, size=(outliers, 1)) * plane.normal
    return plane, points


def test_fit_recovers_a_tilted_plane_despite_outliers():
    rng = np.random.default_rng(1)
    truth, points = _tilted_plane_points(rng, 400, np.array([0.1, -0.8, -0.6]), -0.7, 0.002,
                                         outliers=60)
    plane = fit_plane(points, towards=np.zeros(3))
    assert np.degrees(np.arccos(abs(plane.normal @ truth.normal))) < 0.5
    assert abs(abs(plane.offset) - abs(truth.offset)) < 0.001
    assert plane.normal @ (np.zeros(3) - points.mean(axis=0)) > 0  # towards the cameras
    assert 0.001 < plane.residual < 0.004


def test_prior_normal_decides_a_straight_stroke():
    rng = np.random.default_rng(2)
    up = np.array([0.0, -0.6, -0.8])
    # points along one line: any plane through it fits; the prior picks the table's
    line = np.array([0.5, 0.3, 0.8]) + np.outer(np.linspace(-0.15, 0.15, 100),
                                                np.cross(up, [1.0, 0.0, 0.0]))
    line += rng.normal(size=line.shape) * 0.0005
    plane = fit_plane(line, towards=np.zeros(3), prior_normal=up)
    assert np.degrees(np.arccos(abs(plane.normal @ up))) < 1.0
    with pytest.raises(ValueError, match="three points"):
        fit_plane(line[:2], towards=np.zeros(3))


def test_points_on_plane_invert_the_projection_of_both_cameras():
    rng = np.random.default_rng(3)
    plane = Plane(np.array([0.0, -0.7071, -0.7071]), -0.6)
    origin, e1, e2 = plane.basis()
    truth = origin + rng.uniform(-0.2, 0.2, (50, 1)) * e1 + rng.uniform(-0.2, 0.2, (50, 1)) * e2
    angle = np.deg2rad(2.0)
    R = np.array([[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]])
    t = np.array([-0.12, 0.0, 0.01])
    cameras = [(np.eye(3), np.zeros(3), 600.0), (R, t, 650.0)]
    rays = []
    for R_c, t_c, _ in cameras:
        camera = truth @ R_c.T + t_c
        rays.append(camera / camera[:, 2:3])
    rays[1][::7] = np.nan  # some frames seen by the left camera only
    estimate = points_on_plane(plane, rays, cameras)
    assert np.max(np.linalg.norm(estimate - truth, axis=1)) < 1e-9
    # a pixel of noise in one camera moves the point by about a pixel's width on the plane
    noisy = [rays[0] + np.array([1.0 / 600.0, 0.0, 0.0]), rays[1]]
    shift = np.linalg.norm(points_on_plane(plane, noisy, cameras) - truth, axis=1)
    assert 0.0002 < np.nanmedian(shift) < 0.002
