"""Pinhole projection with OpenCV's lens-distortion model, in plain numpy.

Conventions: camera optical frame x right, y down, z forward (metres); pixel coordinates
(u, v) with u to the right, v down, origin at the centre of the top-left pixel, as in OpenCV.
Distortion vectors follow ``cv2.projectPoints``: (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2,
s3, s4]]]) with 4, 5, 8 or 12 entries. ``cv2.projectPoints`` computes the same numbers, but
its per-call cost (about 1 ms for a thousand points) is too high for a particle filter that
projects tens of thousands of points per frame.
"""

from __future__ import annotations

import cv2
import numpy as np

#: Distortion-vector lengths understood by :func:`distort_normalised` (OpenCV's 14-term
#: tilted-sensor model is not supported).
SUPPORTED_DISTORTION_LENGTHS = (4, 5, 8, 12)


def transform_points(T_b_a: np.ndarray, points_a: np.ndarray) -> np.ndarray:
    """Map points from frame a to frame b with a 4x4 homogeneous transform.

    Parameters
    ----------
    T_b_a : ndarray, shape (4, 4)
        Rigid transform, ``p_b = R p_a + t``.
    points_a : ndarray, shape (..., 3)
        Points in frame a.

    Returns
    -------
    ndarray, shape (..., 3)
        The same points in frame b.
    """
    return points_a @ T_b_a[:3, :3].T + T_b_a[:3, 3]


def invert_transform(T_b_a: np.ndarray) -> np.ndarray:
    """Inverse of a 4x4 rigid transform: returns ``T_a_b``."""
    R = T_b_a[:3, :3]
    T_a_b = np.eye(4)
    T_a_b[:3, :3] = R.T
    T_a_b[:3, 3] = -R.T @ T_b_a[:3, 3]
    return T_a_b


def make_transform(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """4x4 homogeneous transform from a rotation matrix (3, 3) and a translation (3,)."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(t, dtype=np.float64).reshape(3)
    return T


def _padded_distortion(D: np.ndarray) -> np.ndarray:
    D = np.asarray(D, dtype=np.float64).ravel()
    if D.size not in SUPPORTED_DISTORTION_LENGTHS:
        raise ValueError(f"distortion vector has {D.size} terms, expected one of "
                         f"{SUPPORTED_DISTORTION_LENGTHS}")
    return np.concatenate([D, np.zeros(12 - D.size)])


def distort_normalised(xy: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Apply the OpenCV distortion model to normalised image coordinates.

    Parameters
    ----------
    xy : ndarray, shape (n, 2)
        Undistorted normalised coordinates (X/Z, Y/Z).
    D : ndarray, shape (4,), (5,), (8,) or (12,)
        Distortion coefficients.

    Returns
    -------
    ndarray, shape (n, 2)
        Distorted normalised coordinates.
    """
    k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4 = _padded_distortion(D)
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    radial = (1.0 + k1 * r2 + k2 * r4 + k3 * r6) / (1.0 + k4 * r2 + k5 * r4 + k6 * r6)
    xy2 = 2.0 * x * y
    xd = x * radial + p1 * xy2 + p2 * (r2 + 2.0 * x * x) + s1 * r2 + s2 * r4
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + p2 * xy2 + s3 * r2 + s4 * r4
    return np.stack([xd, yd], axis=-1)


def project_points(points_cam: np.ndarray, K: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Project points given in a camera's optical frame to distorted pixel coordinates.

    Same result as ``cv2.projectPoints(points_cam, 0, 0, K, D)`` for points in front of the
    camera. Points with z <= 0 come out as NaN.

    Parameters
    ----------
    points_cam : ndarray, shape (..., 3)
        Points in the camera optical frame, metres.
    K : ndarray, shape (3, 3)
        Camera matrix.
    D : ndarray, shape (4,), (5,), (8,) or (12,)
        Distortion coefficients.

    Returns
    -------
    ndarray, shape (..., 2)
        Pixel coordinates (u, v).
    """
    points = np.asarray(points_cam, dtype=np.float64)
    flat = points.reshape(-1, 3)
    z = flat[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        xy = flat[:, :2] / np.where(z > 0, z, np.nan)[:, None]
    xyd = distort_normalised(xy, D)
    u = K[0, 0] * xyd[:, 0] + K[0, 1] * xyd[:, 1] + K[0, 2]
    v = K[1, 1] * xyd[:, 1] + K[1, 2]
    return np.stack([u, v], axis=-1).reshape(points.shape[:-1] + (2,))


def pixel_rays(pixels: np.ndarray, K: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Undistort pixels to viewing rays in the camera optical frame.

    Parameters
    ----------
    pixels : ndarray, shape (n, 2)
        Distorted pixel coordinates (u, v).
    K, D
        Camera matrix (3, 3) and distortion coefficients.

    Returns
    -------
    ndarray, shape (n, 3)
        Rays (x, y, 1) through each pixel (not unit length): the point at depth z along the
        ray is ``z * ray``. Inverts :func:`project_points` with OpenCV's iterative
        ``cv2.undistortPoints`` (accurate to well below a pixel inside the image).
    """
    pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
    xy = cv2.undistortPoints(pixels, K, np.asarray(D, dtype=np.float64), None, None, None,
                             criteria).reshape(-1, 2)
    return np.column_stack([xy, np.ones(len(xy))])
