import cv2
import numpy as np
import pytest

from wipelab.vision.projection import (invert_transform, make_transform, pixel_rays,
                                       project_points, transform_points)
from wipelab.vision.synthetic_rig import ARMAR_WIDE_D_LEFT, ARMAR_WIDE_K_LEFT

K = ARMAR_WIDE_K_LEFT
RNG = np.random.default_rng(3)


@pytest.mark.parametrize("D", [
    ARMAR_WIDE_D_LEFT[:4],
    ARMAR_WIDE_D_LEFT,
    np.array([-0.3, 0.1, 0.001, -0.002, 0.01, 0.02, -0.01, 0.005]),
    np.array([-0.3, 0.1, 0.001, -0.002, 0.01, 0.02, -0.01, 0.005, 1e-3, -2e-3, 5e-4, 1e-3]),
])
def test_projection_matches_opencv(D):
    points = RNG.uniform([-0.3, -0.2, 0.4], [0.3, 0.2, 1.2], (500, 3))
    expected = cv2.projectPoints(points, np.zeros(3), np.zeros(3), K, D)[0].reshape(-1, 2)
    np.testing.assert_allclose(project_points(points, K, D), expected, atol=1e-9)


def test_pixel_rays_invert_the_armar_distortion_over_the_whole_image():
    grid = np.mgrid[0:640:16, 0:480:16].reshape(2, -1).T.astype(float)
    rays = pixel_rays(grid, K, ARMAR_WIDE_D_LEFT)
    np.testing.assert_allclose(rays[:, 2], 1.0)
    np.testing.assert_allclose(project_points(rays * 0.7, K, ARMAR_WIDE_D_LEFT), grid, atol=1e-6)


def test_points_behind_the_camera_project_to_nan():
    uv = project_points(np.array([[0.0, 0.0, -1.0], [0.1, 0.0, 1.0]]), K, ARMAR_WIDE_D_LEFT)
    assert np.all(np.isnan(uv[0])) and np.all(np.isfinite(uv[1]))


def test_transform_round_trip():
    R = cv2.Rodrigues(np.array([0.3, -0.2, 0.1]))[0]
    T = make_transform(R, [0.1, -0.2, 0.3])
    points = RNG.normal(size=(10, 3))
    np.testing.assert_allclose(transform_points(invert_transform(T), transform_points(T, points)),
                               points, atol=1e-12)


def test_unsupported_distortion_length_is_refused():
    with pytest.raises(ValueError, match="14 terms"):
        project_points(np.array([[0, 0, 1.0]]), K, np.zeros(14))
