"""The compiled sponge likelihood (and colour-blob moments): its bilinear read, the contrast
and coverage of a box rendered as a blurred silhouette, and the contrast's derivatives
against finite differences of its scores."""

import cv2
import numpy as np
import pytest

from tests.vision.rendered_sponge import EYES, POSE, rendered_views
from wipelab.vision._likelihood_kernel import sample_points
from wipelab.vision._moments_kernel import threshold_moments
from wipelab.vision.sampling import sample_bilinear
from wipelab.vision.sponge_likelihood import SilhouetteContrast, score_view

#: Units of the pose's coordinates below: a millimetre is about a pixel in these cameras
#: (0.5 m away, f = 530 px), 0.015 rad (0.86 degrees) turns the box's ends by about as much.
SCALE = np.array([0.001, 0.001, 0.001, 0.015])
#: Where the cameras see the sponge: off the principal point, up left and down right, so
#: that the projection's depth terms count (u - cx and v - cy differ from zero).
PIXELS = (np.array([140.0, 120.0]), np.array([480.0, 370.0]))


@pytest.fixture(scope="module")
def views():
    return rendered_views(PIXELS)


@pytest.fixture(scope="module")
def contrast(views) -> SilhouetteContrast:
    return SilhouetteContrast(views)


def _smooth_image(rng, shape=(300, 340), sigma=4.0) -> np.ndarray:
    noise = rng.random(shape).astype(np.float32)
    image = cv2.GaussianBlur(noise, (0, 0), sigma)
    return (image - image.min()) / (image.max() - image.min())


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


def _directions(count: int) -> np.ndarray:
    """``count`` random unit directions (count, 4) in units of SCALE."""
    directions = np.random.default_rng(0).normal(size=(count, 4))
    return directions / np.linalg.norm(directions, axis=1)[:, None] * SCALE


def test_contrast_peaks_at_the_rendered_pose(views, contrast):
    directions = _directions(200)
    # both cameras: every pose a quarter of a unit away scores less (by 0.0007 at least)
    peak = contrast(POSE[None])[0]
    for radius in (0.25, 1.0, 4.0):
        assert np.all(contrast(POSE + radius * directions) < peak), radius
    # each camera alone: from one unit on (a camera's own peak lies a fraction of a unit
    # away: some poses half a unit off score higher in one camera)
    for samples, image in views:
        # inside minus outside, 1-5 pixels from an outline blurred by 1.5 pixels: 0.80, 0.81
        own_peak = score_view(POSE[None], samples, image)[0][0]
        assert own_peak > 0.78
        for radius in (1.0, 4.0):
            assert np.all(score_view(POSE + radius * directions, samples, image)[0]
                          < own_peak), radius


def test_coverage_is_the_part_of_the_visible_faces_on_the_silhouette(views):
    for samples, image in views:
        coverage = [score_view((POSE + [shift, 0.0, 0.0, 0.0])[None], samples, image)[1][0]
                    for shift in (0.0, 0.02, 0.05, 0.1, 0.2)]
        # 0.929 and 0.99996 at the rendered pose (the first camera sees one side face at a
        # grazing angle, its samples a pixel from the outline); sliding the 11 cm long box
        # off its silhouette, coverage falls to 0
        assert coverage[0] > 0.92
        assert np.all(np.diff(coverage) < 0) and coverage[-1] == 0.0


def test_a_pose_behind_the_camera_reads_nothing(views):
    for (samples, image), eye in zip(views, EYES):
        behind = np.append(eye + 2 * (eye - POSE[:3]), POSE[3])
        contrast_, coverage = score_view(behind[None], samples, image)
        assert contrast_[0] == 0.0 and coverage[0] == 0.0
    # (a pose behind the first camera need not be behind the second)
    behind = np.append(EYES[0] + 2 * (EYES[0] - POSE[:3]), POSE[3])
    value, gradient, hessian = SilhouetteContrast(views[:1]).derivatives(behind)
    assert value == 0.0 and not gradient.any() and not hessian.any()


def _finite_differences(contrast, pose, step):
    """Central differences (gradient (4,), Hessian (4, 4)) of the summed contrast, steps
    ``step`` (4,)."""
    f = lambda offset: contrast((pose + offset)[None])[0]  # noqa: E731
    E, f0 = np.diag(step), f(np.zeros(4))
    gradient = np.array([(f(E[q]) - f(-E[q])) / (2 * step[q]) for q in range(4)])
    hessian = np.empty((4, 4))
    for q in range(4):
        hessian[q, q] = (f(E[q]) - 2 * f0 + f(-E[q])) / step[q] ** 2
        for r in range(q):
            hessian[q, r] = hessian[r, q] = (f(E[q] + E[r]) - f(E[q] - E[r]) - f(E[r] - E[q])
                                             + f(-E[q] - E[r])) / (4 * step[q] * step[r])
    return gradient, hessian


@pytest.mark.parametrize("offset", [[0.0, 0.0, 0.0, 0.0], [0.002, -0.001, 0.001, 0.03],
                                    [-0.003, 0.002, -0.002, -0.05], [0.0, 0.0, 0.004, 0.0],
                                    [0.0, 0.0, 0.0, 0.06], [0.004, -0.004, 0.002, 0.07]])
def test_derivatives_are_those_of_the_scores(contrast, offset):
    pose = POSE + offset
    value, gradient, hessian = contrast.derivatives(pose)
    assert value == pytest.approx(contrast(pose[None])[0], abs=1e-12)
    np.testing.assert_array_equal(hessian, hessian.T)
    # differences one unit wide, as the kernel's image differences are one pixel wide (the
    # scores' bilinear reads kink at every pixel: narrower ones are noisier, not closer)
    fd_gradient, fd_hessian = _finite_differences(contrast, pose, SCALE)
    # per unit: gradients are about 0.1 (0.0015 at the peak), Hessian entries up to 0.13;
    # the kernel differs by at most 0.0021 and 0.0025 (it leaves out the projection's own
    # curvature, and the differences of the scores are only as smooth as bilinear reads)
    np.testing.assert_allclose(gradient * SCALE, fd_gradient * SCALE, rtol=0, atol=0.003)
    np.testing.assert_allclose(hessian * np.outer(SCALE, SCALE),
                               fd_hessian * np.outer(SCALE, SCALE), rtol=0, atol=0.003)


def test_threshold_moments_equal_opencv_moments_of_the_mask():
    rng = np.random.default_rng(2)
    image = _smooth_image(rng, (90, 120), sigma=6.0)
    image[10:20, 30:50] = 0.5  # exactly at the threshold: not counted
    m00, m10, m01 = threshold_moments(image, 0.5)
    mask = cv2.threshold(image, 0.5, 255, cv2.THRESH_BINARY)[1].astype(np.uint8)
    expected = cv2.moments(mask, binaryImage=True)
    assert 0 < m00 < image.size
    assert (m00, m10, m01) == (expected["m00"], expected["m10"], expected["m01"])
