import numpy as np

from wipelab.vision.pose_refinement import newton_step, refine_pose

SCALE = np.array([0.001, 0.001, 0.001, 0.01])
OPTIMUM = np.array([0.01, -0.02, 0.9, 0.3])
# positive definite, correlated, with curvatures of the right size per axis
A = np.diag(1 / SCALE) @ (np.eye(4) + 0.3 * np.ones((4, 4))) @ np.diag(1 / SCALE)


def _quadratic(poses):
    d = np.atleast_2d(poses) - OPTIMUM
    return -np.einsum("ni,ij,nj->n", d, A, d)


def _quadratic_derivatives(pose):
    d = pose - OPTIMUM
    return float(-d @ A @ d), -2 * A @ d, -2 * A


def test_newton_reaches_the_optimum_of_a_quadratic():
    start = OPTIMUM + [0.002, -0.001, 0.002, 0.02]
    pose, value = refine_pose(_quadratic_derivatives, _quadratic, start, SCALE)
    np.testing.assert_allclose(pose, OPTIMUM, atol=1e-9)
    assert value > -1e-12


def test_steps_are_limited_and_climb_where_the_model_is_convex():
    step = newton_step(np.array([1.0, 0, 0, 0]), np.eye(4), SCALE, max_step=4.0)
    assert step[0] > 0 and step[0] <= 4 * SCALE[0] + 1e-15


def test_non_quadratic_peak_is_found_from_a_few_millimetres():
    def score(poses):
        d = (np.atleast_2d(poses) - OPTIMUM) / SCALE
        return np.exp(-0.05 * np.sum(d ** 2, axis=1)) + 0.2 * np.exp(-0.01 * np.sum(d ** 2, axis=1))

    def derivatives(pose):
        h = SCALE * 0.01
        value = score(pose)[0]
        g = np.array([(score(pose + e)[0] - score(pose - e)[0]) / (2 * e.max())
                      for e in np.diag(h)])
        H = np.array([[(score(pose + ei + ej)[0] - score(pose + ei - ej)[0]
                        - score(pose - ei + ej)[0] + score(pose - ei - ej)[0]) / (4 * ei.max() * ej.max())
                       for ej in np.diag(h)] for ei in np.diag(h)])
        return value, g, H

    start = OPTIMUM + SCALE * [3, -2, 3, 2]
    pose, _ = refine_pose(derivatives, score, start, SCALE, iterations=20)
    assert np.all(np.abs(pose - OPTIMUM) < 0.02 * SCALE)
