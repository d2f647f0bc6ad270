"""Forward kinematics and Jacobians of a serial chain read from URDF, in pure numpy.

Used by the IK (fast, no simulator round trips) and checked against PyBullet and a second
URDF parser in the tests. Frames: poses are 4x4 homogeneous matrices mapping child-frame
points to the chain's root frame (``world`` for ARMAR-IIIb).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

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


def quaternion_xyzw_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> unit quaternion (x, y, z, w), w >= 0 (PyBullet order)."""
    m = rotation
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4, (m[1, 0] - m[0, 1]) / s]
    q = np.asarray(q)
    q /= np.linalg.norm(q)
    return -q if q[3] < 0 else q


def rotation_from_quaternion_xyzw(q) -> np.ndarray:
    """Unit quaternion (x, y, z, w) (PyBullet order) -> rotation matrix (3, 3)."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Axis-angle vector (3,) in the root frame that rotates ``current`` onto ``target``."""
    delta = target @ current.T
    angle = np.arccos(np.clip((np.trace(delta) - 1.0) / 2.0, -1.0, 1.0))
    axis = np.array([delta[2, 1] - delta[1, 2], delta[0, 2] - delta[2, 0],
                     delta[1, 0] - delta[0, 1]])
    norm = np.linalg.norm(axis)
    if norm < 1e-12:
        return np.zeros(3)
    return axis / norm * angle


@dataclass(frozen=True)
class UrdfJoint:
    """A joint as URDF states it: origin (4, 4) from the parent link frame, unit axis (3,),
    kind ('revolute', 'continuous', 'prismatic', 'fixed'), limits (rad or m), effort limit
    (N m or N)."""

    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    effort: float = math.inf

    def transform(self, value: float) -> np.ndarray:
        """Parent-link -> child-link transform (4, 4) at joint value ``value``."""
        motion = np.eye(4)
        if self.kind in ("revolute", "continuous"):
            motion[:3, :3] = rotation_about_axis(self.axis, value)
        elif self.kind == "prismatic":
            motion[:3, 3] = self.axis * value
        return self.origin @ motion


def parse_urdf_joints(urdf_text: str) -> dict[str, UrdfJoint]:
    """All joints of a URDF document, by name."""
    joints = {}
    for element in ET.fromstring(urdf_text).iter("joint"):
        origin = element.find("origin")
        xyz = [0.0, 0.0, 0.0] if origin is None else [float(v) for v in
                                                       origin.get("xyz", "0 0 0").split()]
        rpy = [0.0, 0.0, 0.0] if origin is None else [float(v) for v in
                                                       origin.get("rpy", "0 0 0").split()]
        pose = np.eye(4)
        pose[:3, :3] = rotation_from_rpy(rpy)
        pose[:3, 3] = xyz
        axis_element = element.find("axis")
        axis = np.array([1.0, 0.0, 0.0] if axis_element is None else
                        [float(v) for v in axis_element.get("xyz").split()])
        limit = element.find("limit")
        lower = -np.inf if limit is None else float(limit.get("lower", "-inf"))
        upper = np.inf if limit is None else float(limit.get("upper", "inf"))
        effort = np.inf if limit is None else float(limit.get("effort", "inf"))
        name = element.get("name")
        joints[name] = UrdfJoint(name, element.get("type"), element.find("parent").get("link"),
                                 element.find("child").get("link"), pose,
                                 axis / np.linalg.norm(axis), lower, upper, effort)
    return joints


class KinematicChain:
    """The serial chain from the URDF's root to ``tip``, with some joints held fixed.

    Held joints are folded into constant transforms once, so that ``forward`` and
    ``jacobian`` cost a handful of small matrix products (the IK calls them every control
    step).

    Parameters
    ----------
    urdf_text : str
        The URDF document.
    tip : str
        Link whose pose is computed.
    active : sequence of str
        Names of the joints that move (the IK's variables), in the order of ``q``.
    held : dict, optional
        Values (rad or m) of the chain's other movable joints (e.g. the platform pose);
        joints not listed are held at 0.
    """

    def __init__(self, urdf_text: str, tip: str, active, held=None):
        joints = parse_urdf_joints(urdf_text)
        by_child = {j.child: j for j in joints.values()}
        path = []
        link = tip
        while link in by_child:
            path.append(by_child[link])
            link = by_child[link].parent
        path.reverse()
        self.root = link
        self.active = tuple(active)
        names = [j.name for j in path]
        missing = [a for a in self.active if a not in names]
        if missing:
            raise ValueError(f"joints {missing} are not on the chain {self.root} -> {tip}")
        held = dict(held or {})
        # constant transform before each active joint's motion, in q order
        self._before = np.zeros((len(self.active), 4, 4))
        self._axes = np.zeros((len(self.active), 3))
        self._prismatic = np.zeros(len(self.active), dtype=bool)
        pending = np.eye(4)
        for joint in path:
            if joint.name in self.active:
                i = self.active.index(joint.name)
                self._before[i] = pending @ joint.origin
                self._axes[i] = joint.axis
                self._prismatic[i] = joint.kind == "prismatic"
                pending = np.eye(4)
            else:
                pending = pending @ joint.transform(float(held.get(joint.name, 0.0)))
        order = [names.index(a) for a in self.active]
        if order != sorted(order):
            raise ValueError("active joints must be listed from the root to the tip")
        self._tail = pending
        x, y, z = self._axes.T
        zero = np.zeros_like(x)
        self._k = np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1),
                            np.stack([-y, x, zero], -1)], 1)
        self._k2 = self._k @ self._k
        self._revolute = (~self._prismatic).astype(float)
        self._prismatic = self._prismatic.astype(float)
        self._identity = np.broadcast_to(np.eye(4), (len(self.active), 4, 4)).copy()
        self.lower = np.array([joints[a].lower for a in self.active])
        self.upper = np.array([joints[a].upper for a in self.active])

    def _motions(self, q: np.ndarray) -> np.ndarray:
        """Joint motion transforms (n, 4, 4) at ``q`` (Rodrigues for revolute joints)."""
        motion = self._identity.copy()
        angle = q * self._revolute
        s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
        motion[:, :3, :3] += s * self._k + (1.0 - c) * self._k2
        motion[:, :3, 3] = (q * self._prismatic)[:, None] * self._axes
        return motion

    def _joint_frames(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Frames (n, 4, 4) of the active joints (before their motion) and the tip's pose."""
        motions = self._motions(np.asarray(q, dtype=float))
        frames = np.empty_like(motions)
        pose = self._before[0]
        for i in range(len(motions)):
            if i:
                pose = pose @ self._before[i]
            frames[i] = pose
            pose = pose @ motions[i]
        return frames, pose @ self._tail

    def forward(self, q) -> np.ndarray:
        """Pose (4, 4) of ``tip`` in the root frame for active joint values ``q`` (n,)."""
        return self._joint_frames(q)[1]

    def jacobian(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Tip pose (4, 4) and geometric Jacobian (6, n): rows 0-2 linear velocity (m/s per
        unit joint velocity), rows 3-5 angular velocity (rad/s), both in the root frame."""
        frames, pose = self._joint_frames(q)
        axes = (frames[:, :3, :3] @ self._axes[:, :, None])[:, :, 0]
        r = pose[:3, 3] - frames[:, :3, 3]
        lever = np.empty_like(axes)
        lever[:, 0] = axes[:, 1] * r[:, 2] - axes[:, 2] * r[:, 1]
        lever[:, 1] = axes[:, 2] * r[:, 0] - axes[:, 0] * r[:, 2]
        lever[:, 2] = axes[:, 0] * r[:, 1] - axes[:, 1] * r[:, 0]
        jac = np.empty((6, len(axes)))
        jac[:3] = (lever * self._revolute[:, None] + axes * self._prismatic[:, None]).T
        jac[3:] = (axes * self._revolute[:, None]).T
        return pose, jac
