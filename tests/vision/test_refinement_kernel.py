"""The compiled Newton refinement against its numpy reference (pose_refinement)."""

import cv2
import numpy as np
import pytest

from wipelab.vision import _refinement_kernel as kernel
from wipelab.vision.pose_refinement import newton_step, refine_pose
from wipelab.vision.sponge_box import SpongeBox, yaw_rotation
from wipelab.vision.sponge_likelihood import (SilhouetteContrast, SpongeTemplate, ViewImage,
                                              facing_camera, view_samples)

SCALE = np.array([0.001, 0.001, 0.001, 0.015])
BOX = SpongeBox()
POSE = np.array([0.02, -0.01, 0.03, 0.4])
K = np.array([[530.0, 0.0, 320.0], [0.0, 530.0, 240.0], [0.0, 0.0, 1.0]])


def test_solve_matches_lapack_and_reports_singular_matrices():
    rng = np.random.default_rng(0)
    for _ in range(20):
        A = rng.normal(size=(4, 4))
        b = rng.normal(size=4)
        x, regular = kernel.solve(A, b)
        assert regular
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-9, atol=1e-12)
    singular = np.array([[1.0, 2, 0, 0], [2, 4, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    assert not kernel.solve(singular, np.ones(4))[1]


def test_newton_step_matches_the_reference_in_every_branch():
    rng = np.random.default_rng(1)
    curvature = np.diag(1 / SCALE ** 2)
    cases = [(rng.normal(size=4) / SCALE, -curvature),            # concave: Newton step
             (rng.normal(size=4) / SCALE, curvature),             # convex: gradient step
             (rng.normal(size=4) / SCALE, np.zeros((4, 4))),      # singular: gradient step
             (1e3 * rng.normal(size=4) / SCALE, -curvature)]      # clipped
    for gradient, hessian in cases:
        expected = newton_step(gradient, hessian, SCALE, 4.0)
        np.testing.assert_allclose(kernel.newton_step(gradient, hessian, SCALE, 4.0), expected,
                                   rtol=1e-12, atol=1e-15)
        assert np.any(expected != 0)


def _feature_image(centre: np.ndarray, R: np.ndarray, t: np.ndarray) -> ViewImage:
    """A blurred silhouette of the sponge at ``centre`` (yaw POSE[3]), rendered by filling
    its projected corners' hull: the feature the refinement climbs."""
    corners = (BOX.corners() @ yaw_rotation(POSE[3]).T + centre) @ R.T + t
    pixels = corners[:, :2] / corners[:, 2:] * [K[0, 0], K[1, 1]] + K[:2, 2]
    image = np.zeros((480, 640), np.float32)
    cv2.fillConvexPoly(image, cv2.convexHull(np.round(pixels * 16).astype(np.int32)), 1.0,
                       lineType=cv2.LINE_AA, shift=4)
    return ViewImage(cv2.GaussianBlur(image, (0, 0), 1.5), (0.0, 0.0), K, R, t)


@pytest.mark.parametrize("offset", [[0.003, -0.002, 0.002, 0.05], [-0.004, 0.001, -0.003, -0.08],
                                    [0.0005, 0.0, 0.0, 0.0]])
def test_compiled_refinement_takes_the_reference_steps(offset):
    views = []
    for rotation, eye in ((np.array([np.pi - 0.5, 0.1, 0.05]), np.array([0.05, -0.35, 0.5])),
                          (np.array([np.pi - 0.45, -0.1, 0.0]), np.array([0.14, -0.33, 0.5]))):
        R = cv2.Rodrigues(rotation)[0]
        t = -R @ eye
        faces, edges = facing_camera(yaw_rotation(POSE[3]), POSE[:3], eye, BOX)
        samples = view_samples(SpongeTemplate.build(BOX, 0.014, 0.016), R, faces, edges,
                               (0.001, 0.0025, 0.0045))
        views.append((samples, _feature_image(POSE[:3], R, t)))
    contrast = SilhouetteContrast(views)
    start = POSE + offset
    pose, value = contrast.refine(start, SCALE, iterations=8)
    expected, expected_value = refine_pose(contrast.derivatives, contrast, start, SCALE,
                                           iterations=8)
    np.testing.assert_allclose(pose, expected, rtol=0, atol=1e-12)
    assert value == pytest.approx(expected_value, abs=1e-12)
    # and it climbed, over more than a typical step
    assert value > contrast(start[None])[0] + 0.01
    assert np.any(np.abs(pose - start) > SCALE)
