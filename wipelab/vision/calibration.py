"""Stereo calibration files (OpenCV FileStorage), validated at the edge.

File keys (DESIGN.md, "Demo directory"): ``image_width``, ``image_height``, ``K1``, ``D1``,
``K2``, ``D2``, ``R``, ``T`` in the ``cv2.stereoCalibrate`` convention
(``x_right = R x_left + T``, metres) and optionally ``T_world_left`` (4x4, maps points in the
left camera's optical frame to the world frame, REP-103). ``R`` may also be a Rodrigues
vector (3 values).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import check_readable
from wipelab.vision.projection import (SUPPORTED_DISTORTION_LENGTHS, make_transform,
                                       project_points, transform_points)

REQUIRED_KEYS = ("image_width", "image_height", "K1", "D1", "K2", "D2", "R", "T")


@dataclass(frozen=True)
class Camera:
    """One calibrated camera.

    Attributes
    ----------
    K : ndarray, shape (3, 3)
        Camera matrix, pixels.
    D : ndarray, shape (4,), (5,), (8,) or (12,)
        OpenCV distortion coefficients.
    T_cam_ref : ndarray, shape (4, 4)
        Maps points in the reference frame (the left camera's optical frame) to this
        camera's optical frame.
    """

    K: np.ndarray
    D: np.ndarray
    T_cam_ref: np.ndarray

    def project(self, points_ref: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of points (..., 3) given in the reference frame (with distortion)."""
        return project_points(transform_points(self.T_cam_ref, points_ref), self.K, self.D)


@dataclass(frozen=True)
class StereoCalibration:
    """A calibrated stereo pair.

    Attributes
    ----------
    image_size : tuple of int
        (width, height) in pixels.
    K1, D1, K2, D2 : ndarray
        Left and right camera matrices (3, 3) and distortion vectors.
    R : ndarray, shape (3, 3)
        Rotation from the left to the right optical frame.
    T : ndarray, shape (3,)
        Translation, metres: ``x_right = R x_left + T``.
    T_world_left : ndarray, shape (4, 4), or None
        Pose of the left optical frame in the world frame.
    """

    image_size: tuple[int, int]
    K1: np.ndarray
    D1: np.ndarray
    K2: np.ndarray
    D2: np.ndarray
    R: np.ndarray
    T: np.ndarray
    T_world_left: np.ndarray | None = None

    @property
    def left(self) -> Camera:
        """The left camera; its optical frame is the reference frame."""
        return Camera(self.K1, self.D1, np.eye(4))

    @property
    def right(self) -> Camera:
        """The right camera, placed by (R, T)."""
        return Camera(self.K2, self.D2, make_transform(self.R, self.T))

    @property
    def T_track_left(self) -> np.ndarray:
        """Maps left-camera points to the frame tracks are reported in (world if known)."""
        return np.eye(4) if self.T_world_left is None else self.T_world_left

    @property
    def track_frame(self) -> str:
        """Name of the frame tracks are reported in: ``world`` or ``left_optical``."""
        return "left_optical" if self.T_world_left is None else "world"

    @property
    def baseline(self) -> float:
        """Distance between the optical centres, metres."""
        return float(np.linalg.norm(self.T))


def _matrix(fs: cv2.FileStorage, key: str, name: str) -> np.ndarray:
    node = fs.getNode(key)
    if node.empty() or node.isNone():
        raise InputError(f"{name}: missing key {key}")
    value = node.mat()
    if value is None:
        raise InputError(f"{name}: {key} is not a matrix (write it with cv2.FileStorage.write)")
    value = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(value)):
        raise InputError(f"{name}: {key} has NaN or inf entries")
    return value


def _shape_text(value: np.ndarray) -> str:
    return "x".join(str(n) for n in value.shape)


def _check_camera_matrix(K: np.ndarray, key: str, name: str) -> np.ndarray:
    if K.shape != (3, 3):
        raise InputError(f"{name}: {key} must be a 3x3 matrix, got {_shape_text(K)}")
    if K[0, 0] <= 0 or K[1, 1] <= 0 or not np.allclose(K[2], [0, 0, 1]) or K[1, 0] != 0:
        raise InputError(f"{name}: {key} is not a camera matrix "
                         "[[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")
    return K


def _check_distortion(D: np.ndarray, key: str, name: str) -> np.ndarray:
    if D.ndim != 2 or min(D.shape) != 1 or D.size not in SUPPORTED_DISTORTION_LENGTHS:
        raise InputError(f"{name}: {key} must be a 1xN or Nx1 vector with N in "
                         f"{', '.join(map(str, SUPPORTED_DISTORTION_LENGTHS))}, "
                         f"got {_shape_text(D)}")
    return D.ravel()


def _check_rotation(R: np.ndarray, name: str) -> np.ndarray:
    if R.size == 3 and min(R.shape) == 1:
        R = cv2.Rodrigues(R.reshape(3, 1))[0]
    if R.shape != (3, 3):
        raise InputError(f"{name}: R must be a 3x3 rotation matrix or a 3-vector, "
                         f"got {_shape_text(R)}")
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-4) or np.linalg.det(R) < 0:
        raise InputError(f"{name}: R is not a rotation matrix (R R^T != I or det < 0)")
    return R


def load_calibration(path: str | os.PathLike) -> StereoCalibration:
    """Read and validate a stereo calibration file.

    Raises
    ------
    InputError
        Naming the file and the problem: not found, not FileStorage, a missing key, a
        matrix of the wrong shape, a non-rotation R, a zero baseline, a bad T_world_left.
    """
    name = str(check_readable(path))
    try:
        fs = cv2.FileStorage(name, cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError):  # OpenCV's parser errors surface as either
        raise InputError(f"{name}: not an OpenCV FileStorage file (YAML/XML/JSON)") from None
    if not fs.isOpened():
        raise InputError(f"{name}: not an OpenCV FileStorage file (YAML/XML/JSON)")
    try:
        sizes = []
        for key in ("image_width", "image_height"):
            node = fs.getNode(key)
            if node.empty() or node.isNone():
                raise InputError(f"{name}: missing key {key}")
            if not node.isInt() and not node.isReal():
                raise InputError(f"{name}: {key} must be a number")
            value = node.real()
            if value <= 0 or value != int(value):
                raise InputError(f"{name}: {key} must be a positive integer, got {value:g}")
            sizes.append(int(value))
        K1 = _check_camera_matrix(_matrix(fs, "K1", name), "K1", name)
        D1 = _check_distortion(_matrix(fs, "D1", name), "D1", name)
        K2 = _check_camera_matrix(_matrix(fs, "K2", name), "K2", name)
        D2 = _check_distortion(_matrix(fs, "D2", name), "D2", name)
        R = _check_rotation(_matrix(fs, "R", name), name)
        T = _matrix(fs, "T", name)
        if T.size != 3 or min(T.shape) != 1:
            raise InputError(f"{name}: T must be a 3x1 vector, got {_shape_text(T)}")
        T = T.ravel()
        if np.linalg.norm(T) < 1e-6:
            raise InputError(f"{name}: T is zero; the two cameras must be apart")
        T_world_left = None
        node = fs.getNode("T_world_left")
        if not (node.empty() or node.isNone()):
            T_world_left = _matrix(fs, "T_world_left", name)
            if T_world_left.shape != (4, 4):
                raise InputError(f"{name}: T_world_left must be a 4x4 matrix, "
                                 f"got {_shape_text(T_world_left)}")
            if (not np.allclose(T_world_left[3], [0, 0, 0, 1])
                    or not np.allclose(T_world_left[:3, :3] @ T_world_left[:3, :3].T,
                                       np.eye(3), atol=1e-4)
                    or np.linalg.det(T_world_left[:3, :3]) < 0):
                raise InputError(f"{name}: T_world_left is not a rigid transform")
    finally:
        fs.release()
    return StereoCalibration((sizes[0], sizes[1]), K1, D1, K2, D2, R, T, T_world_left)


def save_calibration(path: str | os.PathLike, calibration: StereoCalibration) -> None:
    """Write a calibration as OpenCV FileStorage (format chosen by the suffix, e.g. .yaml)."""
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        fs.write("image_width", int(calibration.image_size[0]))
        fs.write("image_height", int(calibration.image_size[1]))
        fs.write("K1", calibration.K1)
        fs.write("D1", calibration.D1.reshape(1, -1))
        fs.write("K2", calibration.K2)
        fs.write("D2", calibration.D2.reshape(1, -1))
        fs.write("R", calibration.R)
        fs.write("T", calibration.T.reshape(3, 1))
        if calibration.T_world_left is not None:
            fs.write("T_world_left", calibration.T_world_left)
    finally:
        fs.release()
