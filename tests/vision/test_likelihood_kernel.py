"""The compiled sponge likelihood (and colour-blob moments) against their references."""

import cv2
import numpy as np
import pytest

from wipelab.vision._likelihood_kernel import sample_points
from wipelab.vision._moments_kernel import threshold_moments
from wipelab.vision.sampling import sample_bilinear
from wipelab.vision.sponge_box import SpongeBox, yaw_rotation
from wipelab.vision.sponge_likelihood import (SilhouetteContrast, SpongeTemplate, ViewImage,
                                              contrast_derivatives_reference, facing_camera,
                                              score_view, score_view_reference, view_samples)

BOX = SpongeBox()
POSE = np.array([0.02, -0.01, 0.03, 0.4])
K = np.array([[530.0, 0.0, 320.0], [0.0, 530.0, 240.0], [0.0, 0.0, 1.0]])


def _smooth_image(rng, shape=(300, 340), sigma=4.0) -> np.ndarray:
    noise = rng.random(shape).astype(np.float32)
    image = cv2.GaussianBlur(noise, (0, 0), sigma)
    return (image - image.min()) / (image.max() - image.min())


def _camera() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R_cam_track, t_cam_track (a camera 0.6 m above the origin, tilted) and its eye."""
    R = cv2.Rodrigues(np.array([np.pi - 0.5, 0.1, 0.05]))[0]
    eye = np.array([0.05, -0.35, 0.5])
    return R, -R @ eye, eye


@pytest.fixture(scope="module", params=["coarse", "fine"])
def view(request):
    rng = np.random.default_rng(3)
    R, t, eye = _camera()
    template = (SpongeTemplate.build(BOX, 0.03, 0.035) if request.param == "coarse"
                else SpongeTemplate.build(BOX, 0.014, 0.016))
    faces, edges = facing_camera(yaw_rotation(POSE[3]), POSE[:3], eye, BOX)
    samples = view_samples(template, R, faces, edges, (0.001, 0.0025, 0.0045))
    # a window placed around the sponge's pixels
    centre = K @ (R @ POSE[:3] + t)
    origin = (float(np.floor(centre[0] / centre[2])) - 170.0,
              float(np.floor(centre[1] / centre[2])) - 150.0)
    return samples, ViewImage(_smooth_image(rng), origin, K, R, t)


def test_bilinear_read_equals_opencv_on_its_sub_pixel_grid():
    rng = np.random.default_rng(0)
    image = rng.random((40, 50)).astype(np.float32)
    # cv2.remap rounds coordinates to 1/32 pixel: there both reads are the same numbers;
    # points straddle the borders (zero outside) and lie far outside
    uv = np.round(rng.uniform(-3.0, 53.0, (2000, 2)) * 32.0) / 32.0
    uv[:5] = [[-0.5, 3.0], [49.5, 39.5], [1e9, 2.0], [np.nan, 1.0], [-1.0, -1.0]]
    np.testing.assert_allclose(sample_points(image, uv), sample_bilinear(image, uv), atol=2e-6)


def test_bilinear_read_interpolates_exactly_between_the_grid():
    image = np.array([[0.0, 1.0], [2.0, 4.0]], np.float32)
    np.testing.assert_allclose(sample_points(image, np.array([[0.3, 0.7], [0.01, 0.0]])),
                               [0.3 * 0.3 * 1.0 + 0.7 * 0.7 * 2.0 + 0.3 * 0.7 * 4.0, 0.01],
                               rtol=1e-6)


def test_scores_match_the_numpy_reference(view):
    samples, image = view
    rng = np.random.default_rng(1)
    poses = POSE + rng.normal(size=(60, 4)) * [0.01, 0.01, 0.01, 0.2]
    contrast, coverage = score_view(poses, samples, image)
    expected_contrast, expected_coverage = score_view_reference(poses, samples, image)
    # the reference reads on OpenCV's 1/32 pixel grid: about 1e-4 on this smooth image
    np.testing.assert_allclose(contrast, expected_contrast, atol=5e-4)
    np.testing.assert_allclose(coverage, expected_coverage, atol=5e-4)
    assert np.ptp(contrast) > 50 * 5e-4 and np.ptp(coverage) > 50 * 5e-4


def test_points_behind_the_camera_read_nothing(view):
    samples, image = view
    R, t, eye = _camera()
    behind = np.append(eye + 2 * (eye - POSE[:3]), 0.0)  # far behind the camera
    contrast, coverage = score_view(behind[None], samples, image)
    assert contrast[0] == 0.0 and coverage[0] == 0.0
    np.testing.assert_array_equal(score_view_reference(behind[None], samples, image),
                                  (contrast, coverage))


def test_derivatives_match_the_numpy_reference_and_the_scores(view):
    samples, image = view
    contrast = SilhouetteContrast([(samples, image), (samples, image)])
    for pose in (POSE, POSE + [0.003, -0.002, 0.001, 0.05]):
        value, gradient, hessian = contrast.derivatives(pose)
        v, g, h = contrast_derivatives_reference(pose, samples, image)
        assert value == pytest.approx(2 * v, abs=1e-3)
        np.testing.assert_allclose(gradient, 2 * g, atol=2e-3 * np.abs(g).max())
        np.testing.assert_allclose(hessian, 2 * h, atol=2e-3 * np.abs(h).max())
        np.testing.assert_allclose(hessian, hessian.T, atol=1e-12 * np.abs(hessian).max())
        assert value == pytest.approx(contrast(pose[None])[0], abs=1e-12)
        assert np.abs(g).max() > 0.1 and np.abs(h).max() > 100.0


def test_threshold_moments_equal_opencv_moments_of_the_mask():
    rng = np.random.default_rng(2)
    image = _smooth_image(rng, (90, 120), sigma=6.0)
    image[10:20, 30:50] = 0.5  # exactly at the threshold: not counted
    m00, m10, m01 = threshold_moments(image, 0.5)
    mask = cv2.threshold(image, 0.5, 255, cv2.THRESH_BINARY)[1].astype(np.uint8)
    expected = cv2.moments(mask, binaryImage=True)
    assert 0 < m00 < image.size
    assert (m00, m10, m01) == (expected["m00"], expected["m10"], expected["m01"])
