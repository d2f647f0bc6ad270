"""Cameras: pose, intrinsics, projection with the lens model, and the supersampled canvas.

Frames: the world is REP-103 (x forward, y left, z up); a camera's optical frame has x right,
y down, z forward. ``T_world_cam`` (4x4) maps optical-frame points to the world.

A frame is drawn in a *canvas*: an undistorted pinhole image, ``scale`` times finer than the
output, large enough to hold every ray the (distorted) output image sees. :class:`Canvas`
holds the maps that resample it into the output through the lens model (``cv2.remap``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tests.stereo_scenes.lens import distort, undistort


def look_at(eye: np.ndarray, target: np.ndarray, roll: float = 0.0) -> np.ndarray:
    """``T_world_cam`` (4x4) of a camera at ``eye`` whose optical axis points at ``target``,
    image "up" towards world +z, turned by ``roll`` (rad) about the optical axis."""
    forward = np.asarray(target, float) - np.asarray(eye, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    c, s = np.cos(roll), np.sin(roll)
    right, down = c * right + s * down, -s * right + c * down
    T = np.eye(4)
    T[:3, :3] = np.column_stack([right, down, forward])
    T[:3, 3] = eye
    return T


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix (3, 3) by ``angle`` (rad) about ``axis`` (Rodrigues' formula)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


@dataclass
class Camera:
    """A camera with a Brown-Conrady lens.

    Attributes
    ----------
    width, height : int
        Image size, pixels.
    K : ndarray (3, 3)
        Camera matrix (fx, fy, cx, cy; no skew).
    D : ndarray (5,)
        Distortion ``(k1, k2, p1, p2, k3)``.
    T_world_cam : ndarray (4, 4)
        Optical frame -> world.
    """

    width: int
    height: int
    K: np.ndarray
    D: np.ndarray
    T_world_cam: np.ndarray
    T_cam_world: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        self.T_cam_world = np.linalg.inv(self.T_world_cam)

    @property
    def centre(self) -> np.ndarray:
        """Optical centre in the world, (3,)."""
        return self.T_world_cam[:3, 3]

    def to_camera(self, points_world: np.ndarray) -> np.ndarray:
        """Points (..., 3) from the world to the optical frame."""
        return points_world @ self.T_cam_world[:3, :3].T + self.T_cam_world[:3, 3]

    def project(self, points_world: np.ndarray) -> np.ndarray:
        """Distorted pixel coordinates (..., 2) of world points (..., 3) in front of the camera."""
        p = self.to_camera(np.asarray(points_world, float))
        xy = distort(p[..., :2] / p[..., 2:3], self.D)
        return xy * [self.K[0, 0], self.K[1, 1]] + [self.K[0, 2], self.K[1, 2]]


class Canvas:
    """The undistorted, supersampled pinhole image a camera's frames are drawn in.

    Parameters
    ----------
    camera : Camera
    scale : float
        Canvas pixels per output pixel at the image centre.

    Attributes
    ----------
    K : ndarray (3, 3)
        Pinhole camera matrix of the canvas.
    size : (int, int)
        (width, height) of the canvas.
    map_x, map_y : ndarray (height, width) float32
        Canvas coordinates sampled by each output pixel (for ``cv2.remap``).
    """

    def __init__(self, camera: Camera, scale: float):
        self.camera = camera
        self.scale = scale
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64),
                           np.arange(camera.height, dtype=np.float64))
        K = camera.K
        xy_d = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1]], axis=-1)
        xy = undistort(xy_d, camera.D)
        fx, fy = scale * K[0, 0], scale * K[1, 1]
        margin = 8.0
        x0 = np.floor(fx * xy[..., 0].min() - margin)
        y0 = np.floor(fy * xy[..., 1].min() - margin)
        x1 = np.ceil(fx * xy[..., 0].max() + margin)
        y1 = np.ceil(fy * xy[..., 1].max() + margin)
        self.K = np.array([[fx, 0.0, -x0], [0.0, fy, -y0], [0.0, 0.0, 1.0]])
        self.size = (int(x1 - x0), int(y1 - y0))
        self.map_x = (fx * xy[..., 0] - x0).astype(np.float32)
        self.map_y = (fy * xy[..., 1] - y0).astype(np.float32)
        #: largest undistorted normalised radius the image sees
        self.undistorted_reach = float(np.linalg.norm(xy, axis=-1).max())

    def project(self, points_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Canvas pixels (..., 2) and depths (...,) of world points (..., 3)."""
        p = self.camera.to_camera(np.asarray(points_world, float))
        z = p[..., 2]
        safe = np.where(z > 1e-6, z, 1e-6)
        uv = np.stack([self.K[0, 0] * p[..., 0] / safe + self.K[0, 2],
                       self.K[1, 1] * p[..., 1] / safe + self.K[1, 2]], axis=-1)
        return uv, z

    def focal(self) -> float:
        """Mean canvas focal length, pixels."""
        return 0.5 * (self.K[0, 0] + self.K[1, 1])
