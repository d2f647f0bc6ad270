"""Forward kinematics and Jacobians of a serial chain read from URDF (numpy, numba kernels).

Used by the IK (fast, no simulator round trips) and checked against PyBullet and a second
URDF parser in the tests. Frames: poses are 4x4 homogeneous matrices mapping child-frame
points to the chain's root frame (``world`` for ARMAR-IIIb).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels
from wipelab.rotations import rotation_from_rpy


@njit(cache=True)
def rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Axis-angle vector (3,) in the root frame that rotates ``current`` onto ``target``
    (both (3, 3))."""
    delta = np.empty((3, 3))                                   # target current^T
    for i in range(3):
        for j in range(3):
            delta[i, j] = target[i, 0] * current[j, 0] + target[i, 1] * current[j, 1] \
                + target[i, 2] * current[j, 2]
    cosine = min(max((delta[0, 0] + delta[1, 1] + delta[2, 2] - 1.0) / 2.0, -1.0), 1.0)
    axis = np.array([delta[2, 1] - delta[1, 2], delta[0, 2] - delta[2, 0],
                     delta[1, 0] - delta[0, 1]])
    norm = math.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)
    if norm < 1e-12:
        return np.zeros(3)
    return axis / norm * math.acos(cosine)


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
        return self.transforms([value])[0]

    def transforms(self, values) -> np.ndarray:
        """Parent-link -> child-link transforms (n, 4, 4) at joint values ``values`` (n,)."""
        values = np.asarray(values, dtype=float).reshape(-1)
        motion = np.broadcast_to(np.eye(4), (values.size, 4, 4)).copy()
        if self.kind in ("revolute", "continuous"):
            x, y, z = self.axis
            k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
            motion[:, :3, :3] += (np.sin(values)[:, None, None] * k
                                  + (1.0 - np.cos(values))[:, None, None] * (k @ k))
        elif self.kind == "prismatic":
            motion[:, :3, 3] = values[:, None] * self.axis
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


def link_pose(urdf_text: str, link: str, values: dict[str, float] | None = None) -> np.ndarray:
    """Pose (4, 4) of ``link`` in the URDF's root frame with the joints at ``values`` (rad or
    m by name; 0 if absent)."""
    values = dict(values or {})
    by_child = {j.child: j for j in parse_urdf_joints(urdf_text).values()}
    pose = np.eye(4)
    while link in by_child:
        joint = by_child[link]
        pose = joint.transform(float(values.get(joint.name, 0.0))) @ pose
        link = joint.parent
    return pose


class KinematicChain:
    """The serial chain from the URDF's root to ``tip``, with some joints held fixed.

    Held joints are folded into constant transforms once, so that ``forward`` and
    ``jacobian`` cost a handful of small matrix products, compiled with numba (the IK calls
    them every control step).

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
        self.lower = np.array([joints[a].lower for a in self.active])
        self.upper = np.array([joints[a].upper for a in self.active])
        #: The chain for the compiled kernels: (before (n, 4, 4), axes (n, 3),
        #: prismatic (n,) 1.0 / 0.0, tail (4, 4)).
        self.arrays = (np.ascontiguousarray(self._before), np.ascontiguousarray(self._axes),
                       self._prismatic.astype(float), np.ascontiguousarray(self._tail))

    def forward(self, q) -> np.ndarray:
        """Pose (4, 4) of ``tip`` in the root frame for active joint values ``q`` (n,)."""
        return chain_forward(*self.arrays, np.asarray(q, dtype=float))

    def jacobian(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Tip pose (4, 4) and geometric Jacobian (6, n): rows 0-2 linear velocity (m/s per
        unit joint velocity), rows 3-5 angular velocity (rad/s), both in the root frame."""
        jac = np.empty((6, len(self.active)))
        pose = chain_jacobian(*self.arrays, np.asarray(q, dtype=float), jac)
        return pose, jac


# -- compiled kernels (numba): the IK calls them every control period ------------------------

@njit(cache=True)
def _joint_motion(axis: np.ndarray, prismatic: float, value: float, motion: np.ndarray) -> None:
    """Write the motion (4, 4) of one joint into ``motion`` (whose bottom row is 0 0 0 1):
    Rodrigues' rotation about ``axis`` (3,) or a translation along it."""
    if prismatic:
        for r in range(3):
            for k in range(3):
                motion[r, k] = 1.0 if r == k else 0.0
            motion[r, 3] = axis[r] * value
        return
    x, y, z = axis[0], axis[1], axis[2]
    s, c = math.sin(value), math.cos(value)
    v = 1.0 - c
    motion[0, 0], motion[0, 1], motion[0, 2] = c + x * x * v, x * y * v - z * s, x * z * v + y * s
    motion[1, 0], motion[1, 1], motion[1, 2] = x * y * v + z * s, c + y * y * v, y * z * v - x * s
    motion[2, 0], motion[2, 1], motion[2, 2] = x * z * v - y * s, y * z * v + x * s, c + z * z * v
    motion[0, 3], motion[1, 3], motion[2, 3] = 0.0, 0.0, 0.0


@njit(cache=True)
def _compose(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """out = a @ b for rigid transforms (4, 4) (bottom row 0 0 0 1; ``out``'s already is),
    in plain loops: at this size a BLAS call and an allocation cost more than the 36
    products."""
    for r in range(3):
        a0, a1, a2 = a[r, 0], a[r, 1], a[r, 2]
        for k in range(4):
            out[r, k] = a0 * b[0, k] + a1 * b[1, k] + a2 * b[2, k]
        out[r, 3] += a[r, 3]


@njit(cache=True)
def chain_frames(before, axes, prismatic, tail, q, origins, joint_axes) -> np.ndarray:
    """Forward kinematics of a chain given as :attr:`KinematicChain.arrays`.

    Fills ``origins`` (n, 3) and ``joint_axes`` (n, 3) with each active joint's position and
    unit axis in the root frame; returns the tip pose (4, 4).
    """
    pose, joint, motion = np.eye(4), np.eye(4), np.eye(4)
    for i in range(q.size):
        _compose(pose, before[i], joint)
        for r in range(3):
            origins[i, r] = joint[r, 3]
            joint_axes[i, r] = (joint[r, 0] * axes[i, 0] + joint[r, 1] * axes[i, 1]
                                + joint[r, 2] * axes[i, 2])
        _joint_motion(axes[i], prismatic[i], q[i], motion)
        _compose(joint, motion, pose)
    tip = np.eye(4)
    _compose(pose, tail, tip)
    return tip


@njit(cache=True)
def chain_forward(before, axes, prismatic, tail, q) -> np.ndarray:
    """Tip pose (4, 4) of a chain given as :attr:`KinematicChain.arrays` at ``q`` (n,)."""
    n = q.size
    return chain_frames(before, axes, prismatic, tail, q, np.empty((n, 3)), np.empty((n, 3)))


@njit(cache=True)
def chain_jacobian(before, axes, prismatic, tail, q, jac) -> np.ndarray:
    """Tip pose (4, 4); fills ``jac`` (6, n) with the geometric Jacobian in the root frame
    (rows 0-2 linear, 3-5 angular velocity)."""
    n = q.size
    origins, joint_axes = np.empty((n, 3)), np.empty((n, 3))
    pose = chain_frames(before, axes, prismatic, tail, q, origins, joint_axes)
    for i in range(n):
        a = joint_axes[i]
        if prismatic[i]:
            for r in range(3):
                jac[r, i] = a[r]
                jac[3 + r, i] = 0.0
        else:
            rx, ry, rz = pose[0, 3] - origins[i, 0], pose[1, 3] - origins[i, 1], \
                pose[2, 3] - origins[i, 2]
            jac[0, i] = a[1] * rz - a[2] * ry
            jac[1, i] = a[2] * rx - a[0] * rz
            jac[2, i] = a[0] * ry - a[1] * rx
            for r in range(3):
                jac[3 + r, i] = a[r]
    return pose


forget_stale_kernels(__name__)
