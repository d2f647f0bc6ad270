"""The Newton pose refinement: its linear solve, its step rule, and the refinement of a box
pose on rendered silhouettes."""

import numpy as np
import pytest

from tests.vision.rendered_sponge import POSE, rendered_contrast
from wipelab.vision.pose_refinement import newton_step, solve
from wipelab.vision.sponge_likelihood import SilhouetteContrast

SCALE = np.array([0.001, 0.001, 0.001, 0.015])   # the box tracker's refine_steps
MAX_STEP = 4.0
TOLERANCE = 0.1                                   # SilhouetteContrast.refine's default
# a concave quadratic -d.A.d, d = pose - OPTIMUM: correlated, curvatures of the axes' size
OPTIMUM = np.array([0.01, -0.02, 0.9, 0.3])
A = np.diag(1 / SCALE) @ (np.eye(4) + 0.3 * np.ones((4, 4))) @ np.diag(1 / SCALE)


def test_solve_matches_lapack_and_reports_singular_matrices():
    rng = np.random.default_rng(0)
    for _ in range(20):
        M = rng.normal(size=(4, 4))
        b = rng.normal(size=4)
        x, regular = solve(M, b)
        assert regular
        np.testing.assert_allclose(x, np.linalg.solve(M, b), rtol=1e-9, atol=1e-12)
    # a zero on the diagonal: solvable only by pivoting
    permuted = np.array([[0.0, 2, 0, 0], [3, 0, 0, 0], [0, 0, 0, 5], [0, 0, 7, 0]])
    x, regular = solve(permuted, np.array([2.0, 3, 5, 7]))
    assert regular
    np.testing.assert_allclose(x, np.ones(4), rtol=1e-15)
    singular = np.array([[1.0, 2, 0, 0], [2, 4, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    assert not solve(singular, np.ones(4))[1]
    assert not solve(np.zeros((4, 4)), np.ones(4))[1]


def _quadratic_model(pose):
    """Gradient and Hessian of the concave quadratic at ``pose``."""
    return -2 * A @ (pose - OPTIMUM), -2 * A


def test_newton_step_lands_on_the_maximum_of_a_concave_quadratic():
    for offset in ([0.002, -0.001, 0.002, 0.02], [-0.0005, 0.0, 0.001, -0.03]):
        pose = OPTIMUM + offset
        step = newton_step(*_quadratic_model(pose), SCALE, MAX_STEP)
        np.testing.assert_allclose(pose + step, OPTIMUM, rtol=0, atol=1e-12)


def test_newton_step_clips_each_component_to_max_step_scales():
    offset = np.array([0.02, -0.001, -0.03, 0.5])   # Newton step -offset: x, z, yaw too long
    step = newton_step(*_quadratic_model(OPTIMUM + offset), SCALE, MAX_STEP)
    limit = MAX_STEP * SCALE
    np.testing.assert_allclose(step, [-limit[0], 0.001, limit[2], -limit[3]], rtol=1e-9)


def test_newton_step_climbs_the_gradient_where_the_model_does_not_curve_down():
    gradient = np.array([3.0, -1.0, 0.5, -2e4]) / SCALE
    limit = MAX_STEP * SCALE
    # convex: the Newton step would go to the minimum; a gradient step, divided by the
    # curvature along each axis (yaw's gradient is so steep that its step is the limit)
    curvature = np.array([1e4, 2e3, 1e3, 1e3]) / SCALE ** 2
    step = newton_step(gradient, np.diag(curvature), SCALE, MAX_STEP)
    np.testing.assert_allclose(step, [3e-4 * SCALE[0], -5e-4 * SCALE[1], 5e-4 * SCALE[2],
                                      -limit[3]], rtol=1e-12)
    # singular (flat): a full step, up the gradient, on every axis
    step = newton_step(gradient, np.zeros((4, 4)), SCALE, MAX_STEP)
    np.testing.assert_allclose(step, np.sign(gradient) * limit, rtol=1e-12)
    # a saddle whose Newton step goes downhill (up in yaw, the convex axis): climbs instead
    saddle = np.diag([-1.0, -1.0, -1.0, 1.0]) / SCALE ** 2
    step = newton_step(np.array([0.0, 0.0, 0.0, 1.0]) / SCALE, saddle, SCALE, MAX_STEP)
    np.testing.assert_allclose(step, [0.0, 0.0, 0.0, SCALE[3]], rtol=1e-12)


@pytest.fixture(scope="module")
def contrast() -> SilhouetteContrast:
    """The summed contrast of two cameras 0.6 m apart: its peak is the rendered pose."""
    return rendered_contrast()


@pytest.mark.parametrize("offset", [[0.003, -0.002, 0.002, 0.05], [-0.004, 0.001, -0.003, -0.08],
                                    [0.0005, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.06],
                                    [0.006, -0.006, 0.004, 0.1], [-0.008, 0.008, 0.004, 0.1]])
def test_refinement_reaches_the_true_pose_from_millimetres_away(contrast, offset):
    # (from the last start, steps along the gradient rather than the Newton step carry it
    # there in 8 iterations)
    start = POSE + offset
    pose, value = contrast.refine(start, SCALE, iterations=8, max_step=MAX_STEP,
                                  tolerance=TOLERANCE)
    # within one stopping tolerance (0.1 mm, 0.086 degrees) per axis; it reaches 0.06 mm
    # and 0.035 degrees
    assert np.all(np.abs(pose - POSE) < TOLERANCE * SCALE), (pose - POSE) / SCALE
    assert value == pytest.approx(contrast(pose[None])[0], abs=1e-12)
    assert value > contrast(start[None])[0]


def test_refinement_does_not_move_from_the_true_pose(contrast):
    pose, value = contrast.refine(POSE, SCALE, iterations=8, max_step=MAX_STEP,
                                  tolerance=TOLERANCE)
    np.testing.assert_array_equal(pose, POSE)   # the first Newton step is below tolerance
    assert value == pytest.approx(contrast(POSE[None])[0], abs=1e-12)
