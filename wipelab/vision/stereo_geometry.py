"""Triangulation of pixel pairs with a calibrated stereo pair (``cv2.triangulatePoints``)."""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.projection import pixel_rays


def triangulate_pixels(calibration: StereoCalibration, uv_left: np.ndarray,
                       uv_right: np.ndarray) -> np.ndarray:
    """3D points from matching distorted pixels in both images.

    Parameters
    ----------
    calibration : StereoCalibration
    uv_left, uv_right : ndarray, shape (n, 2)
        Matching pixel coordinates.

    Returns
    -------
    ndarray, shape (n, 3)
        Points in the left camera's optical frame, metres (linear DLT on undistorted,
        normalised coordinates).
    """
    left = pixel_rays(uv_left, calibration.K1, calibration.D1)[:, :2]
    right = pixel_rays(uv_right, calibration.K2, calibration.D2)[:, :2]
    P1 = np.hstack([np.eye(3), np.zeros((3, 1))])
    P2 = np.hstack([calibration.R, calibration.T.reshape(3, 1)])
    homogeneous = cv2.triangulatePoints(P1, P2, left.T.astype(np.float64),
                                        right.T.astype(np.float64))
    return (homogeneous[:3] / homogeneous[3]).T


def reprojection_errors(calibration: StereoCalibration, points_left: np.ndarray,
                        uv_left: np.ndarray, uv_right: np.ndarray) -> np.ndarray:
    """Larger of the two cameras' reprojection errors per point, pixels, shape (n,)."""
    error_left = np.linalg.norm(calibration.left.project(points_left) - uv_left, axis=-1)
    error_right = np.linalg.norm(calibration.right.project(points_left) - uv_right, axis=-1)
    return np.maximum(error_left, error_right)


def closest_point_of_rays(origin_a: np.ndarray, direction_a: np.ndarray,
                          origin_b: np.ndarray, direction_b: np.ndarray) -> np.ndarray | None:
    """Midpoint of the shortest segment between two rays (all (3,), one frame), or None if
    they are parallel or it lies behind either origin."""
    w = origin_a - origin_b
    a, b, c = direction_a @ direction_a, direction_a @ direction_b, direction_b @ direction_b
    d, e = direction_a @ w, direction_b @ w
    denominator = a * c - b * b
    if denominator <= 1e-12 * a * c:
        return None
    s = (b * e - c * d) / denominator
    t = (a * e - b * d) / denominator
    if s <= 0 or t <= 0:
        return None
    return 0.5 * (origin_a + s * direction_a + origin_b + t * direction_b)
