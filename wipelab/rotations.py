"""Rotations: roll-pitch-yaw, axis-angle and quaternions (x, y, z, w; PyBullet's and Rerun's
order) to and from 3 x 3 matrices. Plain numpy, no compiled kernels: the vision stages use
them without loading numba."""

from __future__ import annotations

import numpy as np


def rotation_from_rpy(rpy) -> np.ndarray:
    """URDF roll-pitch-yaw (fixed axes x, y, z; rad) -> rotation matrix (3, 3)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def rotation_about_axis(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: rotation (3, 3) by ``angle`` (rad) about the unit ``axis`` (3,)."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def rpy_from_rotation(rotation: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`rotation_from_rpy` (pitch in [-pi/2, pi/2]; roll = 0 at gimbal lock)."""
    pitch = float(np.arcsin(np.clip(-rotation[2, 0], -1.0, 1.0)))
    if abs(rotation[2, 0]) > 1.0 - 1e-12:
        return 0.0, pitch, float(np.arctan2(-rotation[0, 1], rotation[1, 1]))
    roll = float(np.arctan2(rotation[2, 1], rotation[2, 2]))
    yaw = float(np.arctan2(rotation[1, 0], rotation[0, 0]))
    return roll, pitch, yaw


def quaternions_xyzw_from_rotations(rotations: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) -> unit quaternions (n, 4) (x, y, z, w), w >= 0 (PyBullet
    order). Shepperd's method: each row uses the best-conditioned of its four formulas."""
    m = np.asarray(rotations, dtype=float).reshape(-1, 3, 3)
    m00, m11, m22 = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    trace = m00 + m11 + m22
    branch = np.where(trace > 0, 0, np.where((m00 > m11) & (m00 > m22), 1,
                                             np.where(m11 > m22, 2, 3)))
    s = 2.0 * np.sqrt(np.maximum(np.choose(branch, [trace + 1.0, 1.0 + m00 - m11 - m22,
                                                    1.0 + m11 - m00 - m22,
                                                    1.0 + m22 - m00 - m11]), 1e-300))
    a, b, c = m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]
    d, e, f = m[:, 0, 1] + m[:, 1, 0], m[:, 0, 2] + m[:, 2, 0], m[:, 1, 2] + m[:, 2, 1]
    quarter = s / 4
    q = np.stack([np.choose(branch, [a / s, quarter, d / s, e / s]),
                  np.choose(branch, [b / s, d / s, quarter, f / s]),
                  np.choose(branch, [c / s, e / s, f / s, quarter]),
                  np.choose(branch, [quarter, a / s, b / s, c / s])], axis=1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(q[:, 3:] < 0, -q, q)


def quaternion_xyzw_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> unit quaternion (x, y, z, w), w >= 0 (PyBullet order)."""
    return quaternions_xyzw_from_rotations(rotation)[0]


def rotations_from_quaternions_xyzw(quaternions) -> np.ndarray:
    """Quaternions (n, 4) (x, y, z, w) (PyBullet order; normalised here) -> rotation matrices
    (n, 3, 3)."""
    q = np.asarray(quaternions, dtype=float).reshape(-1, 4)
    x, y, z, w = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w),
                               2 * (x * z + y * w)], -1),
                     np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z),
                               2 * (y * z - x * w)], -1),
                     np.stack([2 * (x * z - y * w), 2 * (y * z + x * w),
                               1 - 2 * (x * x + y * y)], -1)], 1)


def rotation_from_quaternion_xyzw(q) -> np.ndarray:
    """Unit quaternion (x, y, z, w) (PyBullet order) -> rotation matrix (3, 3)."""
    return rotations_from_quaternions_xyzw(q)[0]
