"""Brown-Conrady lens distortion (OpenCV's 5-coefficient model), forward and inverse, numpy.

With normalised pinhole coordinates ``(x, y) = (X/Z, Y/Z)`` and ``r^2 = x^2 + y^2``::

    x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
    y' = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y

``D = (k1, k2, p1, p2, k3)``, the order of ``cv2.projectPoints``. The inverse (used to build
the image's resampling maps) is Newton's method on this forward model.
"""

from __future__ import annotations

import numpy as np


def distort(xy: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Distorted normalised coordinates (..., 2) of undistorted ones (..., 2)."""
    k1, k2, p1, p2, k3 = np.asarray(D, dtype=np.float64)
    x, y = xy[..., 0], xy[..., 1]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


def _jacobian(x: np.ndarray, y: np.ndarray, D: np.ndarray):
    k1, k2, p1, p2, k3 = D
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)  # d radial / d(r^2)
    dxx = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x
    dxy = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y
    dyx = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y
    dyy = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x
    return dxx, dxy, dyx, dyy


def undistort(xy_distorted: np.ndarray, D: np.ndarray, iterations: int = 60) -> np.ndarray:
    """Undistorted normalised coordinates (..., 2) whose :func:`distort` is ``xy_distorted``.

    Newton's method from the distorted point; exact to ~1e-12 wherever the model is monotonic
    (:func:`monotonic_radius`).
    """
    D = np.asarray(D, dtype=np.float64)
    target = np.asarray(xy_distorted, dtype=np.float64)
    xy = target.copy()
    for _ in range(iterations):
        residual = distort(xy, D) - target
        dxx, dxy, dyx, dyy = _jacobian(xy[..., 0], xy[..., 1], D)
        det = dxx * dyy - dxy * dyx
        det = np.where(np.abs(det) < 1e-9, 1e-9, det)
        step = np.stack([(dyy * residual[..., 0] - dxy * residual[..., 1]) / det,
                         (-dyx * residual[..., 0] + dxx * residual[..., 1]) / det], axis=-1)
        # damped: a step never moves a point by more than a quarter of its radius (+0.05)
        size = np.linalg.norm(step, axis=-1, keepdims=True)
        limit = 0.25 * np.linalg.norm(xy, axis=-1, keepdims=True) + 0.05
        xy -= step * np.minimum(1.0, limit / np.maximum(size, 1e-300))
        if np.max(np.abs(residual)) < 1e-13:
            break
    return xy


def monotonic_radius(D: np.ndarray, limit: float = 4.0, min_slope: float = 0.15) -> float:
    """Largest undistorted radius up to ``limit`` below which the radial distortion keeps a
    slope ``d r_d / d r`` of at least ``min_slope`` (so the image does not fold)."""
    k1, k2, _, _, k3 = np.asarray(D, dtype=np.float64)
    r = np.linspace(0.0, limit, 4001)
    r2 = r * r
    slope = 1.0 + 3.0 * k1 * r2 + 5.0 * k2 * r2 * r2 + 7.0 * k3 * r2 * r2 * r2
    bad = np.nonzero(slope < min_slope)[0]
    return float(limit if bad.size == 0 else r[bad[0]])
