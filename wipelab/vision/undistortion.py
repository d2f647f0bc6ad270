"""Undistorted image windows: resample a wide-angle frame locally into a pinhole image.

The tracker scores thousands of sample points per frame; projecting them through a plain
pinhole (no distortion polynomial) into a window that was resampled once through the lens
model is much cheaper than distorting every point.
"""

from __future__ import annotations

import cv2
import numpy as np


class Undistorter:
    """Resample windows of a camera's frames into an undistorted (pinhole) image.

    The undistorted canvas is large enough to hold every pixel of the distorted frame (a
    wide-angle lens's corners land outside the frame's own rectangle); its camera matrix
    ``K`` is the camera's with the principal point moved accordingly.

    Parameters
    ----------
    K, D : ndarray
        Camera matrix and distortion.
    size : tuple of int
        (width, height) of the frames.
    """

    def __init__(self, K: np.ndarray, D: np.ndarray, size: tuple[int, int]):
        width, height = size
        edge = np.concatenate([np.column_stack([np.linspace(0, width - 1, 64), np.full(64, y)])
                               for y in (0, height - 1)]
                              + [np.column_stack([np.full(48, x), np.linspace(0, height - 1, 48)])
                                 for x in (0, width - 1)])
        rays = cv2.undistortPoints(edge.reshape(-1, 1, 2), K, D).reshape(-1, 2)
        ideal = rays @ K[:2, :2].T + K[:2, 2]
        low = np.floor(np.minimum(ideal.min(axis=0), 0.0)) - 1
        high = np.ceil(np.maximum(ideal.max(axis=0), [width - 1, height - 1])) + 1
        self.K = K.copy()
        self.K[:2, 2] -= low
        self.size = tuple(int(v) for v in np.minimum(high - low + 1, 3 * np.array(size)))
        self.K_distorted, self.D = K, D
        self.frame_size = (int(width), int(height))
        map_u, map_v = cv2.initUndistortRectifyMap(K, D, None, self.K, self.size, cv2.CV_32FC1)
        # fixed-point maps (1/32 pixel) make the per-frame resampling several times faster
        self.map_xy, self.map_fraction = cv2.convertMaps(map_u, map_v, cv2.CV_16SC2)

    def window(self, frame: np.ndarray, x0: int, y0: int, x1: int, y1: int,
               step: int = 1) -> np.ndarray:
        """Undistorted pixels [y0, y1) x [x0, x1) of ``frame`` (black outside the frame);
        with ``step`` > 1 only every step-th row and column (window pixel (i, j) is canvas
        pixel (x0 + j step, y0 + i step))."""
        return cv2.remap(frame, self.map_xy[y0:y1:step, x0:x1:step],
                         self.map_fraction[y0:y1:step, x0:x1:step],
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)


def pinhole(points: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Pixels (..., 2) of camera-frame points (..., 3) in an undistorted image (NaN if z <= 0)."""
    z = points[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / np.where(z > 1e-6, z, np.nan)
    x, y = points[..., 0] * inverse, points[..., 1] * inverse
    return np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], axis=-1)
