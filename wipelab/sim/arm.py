"""The controller's model of the right arm: posture for a task, then IK along the path.

Two stages, as a robot would do it:

1. :meth:`RightArm.posture_for` chooses how far the torso leans forward (hip pitch, from
   upright in 5 deg steps up to 40 deg) so that the arm alone reaches every sample point of
   the task with margin from its joint limits, and returns the torso posture, the arm's
   posture at the centre of the task and the TCP orientation there (the grasp's R_ref: the
   sponge is grasped for the task, see :mod:`wipelab.sim.sponge`).
2. :meth:`RightArm.tracker` returns an IK on the 7-DOF arm alone with the torso held at that
   posture, which the control loop calls every period. Only the TCP position is controlled
   (plus a null-space pull to the task's rest posture); the hand's orientation follows the
   arm, as in the paper.

The controller knows the nominal kinematics (the URDF) and nothing about the sponge.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from wipelab.sim.armar3 import (RIGHT_ARM_JOINTS, TORSO_JOINTS, Box, Sphere,
                                armar3b_description, armar3b_urdf_path)
from wipelab.sim.ik import ArmIK, IKParams
from wipelab.rotations import rotation_from_rpy
from wipelab.sim.kinematics import KinematicChain, parse_urdf_joints

#: A comfortable right-arm posture to start the posture search from (rad): elbow bent,
#: forearm rolled so that the palm faces the midline.
ARM_SEED = np.radians([-30.0, 0.0, 30.0, -55.0, 60.0, 0.0, 10.0])
#: Hip pitch values tried, upright first (rad; negative leans forward).
HIP_PITCHES = np.radians(-np.arange(0.0, 41.0, 5.0))
#: Required margin (rad) of every arm joint from its limits at every sample point.
LIMIT_MARGIN = np.radians(5.0)
#: Largest position error (m) at a sample point for it to count as reached.
REACH_TOLERANCE = 0.002
#: Fraction of the IK's joint speed limit that a planned movement may use (the rest is for
#: the force feedback's corrections).
SPEED_FRACTION = 0.95


@dataclass(frozen=True)
class TaskPosture:
    """Result of :meth:`RightArm.posture_for`."""

    torso: np.ndarray           # (3,) rad, held while wiping
    arm: np.ndarray             # (7,) rad at the centre, the rest posture of the tracker
    tcp_rotation: np.ndarray    # (3, 3) TCP orientation at the centre (R_ref of the grasp)
    error: float                # m: largest position error over the sample points
    margin: float               # rad: smallest distance of an arm joint from a limit

    def reaches(self) -> bool:
        """Every sample point within REACH_TOLERANCE, with LIMIT_MARGIN from the limits."""
        return self.error < REACH_TOLERANCE and self.margin >= LIMIT_MARGIN


class RightArm:
    """Kinematics of torso + right arm for a robot whose platform stands at ``platform``
    (dict of platform joint values: x, y in m, yaw in rad)."""

    def __init__(self, platform: dict[str, float], ik: IKParams = IKParams()):
        self.urdf_text = armar3b_urdf_path().read_text()
        self.platform = dict(platform)
        self.ik_params = ik
        self._body_chains = None

    def arm_ik(self, torso: np.ndarray, rest: np.ndarray) -> ArmIK:
        """IK of the 7 arm joints with the torso held at ``torso`` (3,) (rad), pulled to
        ``rest`` (7,)."""
        held = dict(self.platform)
        held.update(zip(TORSO_JOINTS, torso))
        chain = KinematicChain(self.urdf_text, "tcp_r", RIGHT_ARM_JOINTS, held=held)
        return ArmIK(chain, 0, rest, self.ik_params)

    def _evaluate(self, torso: np.ndarray, centre: np.ndarray, points: np.ndarray
                  ) -> TaskPosture:
        ik = self.arm_ik(torso, ARM_SEED)
        arm, error = ik.solve(ARM_SEED, centre, max_iterations=300)
        ik = self.arm_ik(torso, arm)
        margin = float(np.min(np.minimum(arm - ik.chain.lower, ik.chain.upper - arm)))
        for point in points:
            q, point_error = ik.solve(arm, point, max_iterations=150)
            error = max(error, point_error)
            margin = min(margin, float(np.min(np.minimum(q - ik.chain.lower,
                                                           ik.chain.upper - q))))
        return TaskPosture(torso, arm, ik.chain.forward(arm)[:3, :3], error, margin)

    def postures(self, centre, points, first_pitch: float | None = None
                 ) -> Iterator[TaskPosture]:
        """Postures for a task centred at ``centre`` (3,) that visits ``points`` (k, 3)
        (m, world), one per torso lean of :data:`HIP_PITCHES`, least forward lean first
        (``first_pitch`` first if given: e.g. the one the reach map found); each is solved
        when it is asked for."""
        centre = np.asarray(centre, dtype=float)
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        order = sorted(HIP_PITCHES, key=lambda pitch: (first_pitch is None
                                                         or abs(pitch - first_pitch) > 1e-9))
        for pitch in order:
            yield self._evaluate(np.array([pitch, 0.0, 0.0]), centre, points)

    def posture_for(self, centre, points, first_pitch: float | None = None) -> TaskPosture:
        """The first of :meth:`postures` that reaches every point with :data:`LIMIT_MARGIN`;
        if none does, the one with the smallest error."""
        best = None
        for posture in self.postures(centre, points, first_pitch):
            if posture.reaches():
                return posture
            if best is None or (posture.error, -posture.margin) < (best.error, -best.margin):
                best = posture
        return best

    def tracker(self, posture: TaskPosture) -> ArmIK:
        """IK on the 7 arm joints with the torso held at ``posture.torso``."""
        return self.arm_ik(posture.torso, posture.arm)

    def body_points(self, torso, arm) -> np.ndarray:
        """Points (k, 3) (m, world) on the torso, the right arm and the hand (their shapes in
        the robot description: corners and faces of boxes, rings of cylinders, poles of
        spheres) at the torso (3,) and arm (7,) joint values."""
        q = np.concatenate([np.asarray(torso, dtype=float), np.asarray(arm, dtype=float)])
        return np.concatenate([_apply(chain.forward(q[active]), local)
                               for chain, active, local in self._bodies()])

    def _bodies(self) -> list[tuple[KinematicChain, np.ndarray, np.ndarray]]:
        """(chain to the link, indices of its joints in torso + arm q, points (k, 3) in the
        link frame) for each link of :data:`BODY_LINKS`; built once."""
        if self._body_chains is None:
            joints = parse_urdf_joints(self.urdf_text)
            by_child = {j.child: j for j in joints.values()}
            links = {link.name: link for link in armar3b_description()[1]}
            moving = TORSO_JOINTS + RIGHT_ARM_JOINTS
            self._body_chains = []
            for name in BODY_LINKS:
                on_chain, link = [], name
                while link in by_child:
                    on_chain.append(by_child[link].name)
                    link = by_child[link].parent
                active = [j for j in moving if j in on_chain]
                chain = KinematicChain(self.urdf_text, name, active, held=self.platform)
                local = np.concatenate([shape_points(shape) for shape in links[name].shapes])
                self._body_chains.append((chain, np.array([moving.index(j) for j in active]),
                                          local))
        return self._body_chains


#: Links whose shapes are checked for clearance from the surface.
BODY_LINKS = ("torso", "upperarm_r_link", "elbow_r_link", "underarm_r_link", "wrist_2_r_link",
              "hand_r")


def _apply(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (k, 3) moved by a pose (4, 4)."""
    return points @ pose[:3, :3].T + pose[:3, 3]


def shape_points(shape) -> np.ndarray:
    """Points (k, 3) on a shape of the robot description, in its link's frame: a box's
    corners, edge midpoints and face centres; a cylinder's end and middle rings of 12; a
    sphere's 6 poles."""
    if isinstance(shape, Box):
        grid = np.stack(np.meshgrid(*[np.linspace(-0.5, 0.5, 3)] * 3, indexing="ij"), -1)
        local = grid.reshape(-1, 3) * np.asarray(shape.size)
        return local @ rotation_from_rpy(shape.rpy).T + np.asarray(shape.xyz)
    if isinstance(shape, Sphere):
        return np.asarray(shape.xyz) + shape.radius * np.concatenate([np.eye(3), -np.eye(3)])
    start, end = np.asarray(shape.start, dtype=float), np.asarray(shape.end, dtype=float)
    axis = (end - start) / np.linalg.norm(end - start)
    side = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    other = np.cross(axis, side)
    angles = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    ring = shape.radius * (np.cos(angles)[:, None] * side + np.sin(angles)[:, None] * other)
    return np.concatenate([start + f * (end - start) + ring for f in (0.0, 0.5, 1.0)])


def phase_rate_limit(tracker: ArmIK, posture: TaskPosture, points, velocities,
                     joint_speed_limit: float) -> float:
    """Largest Omega (rad/s) at which the arm can follow a periodic path.

    The path's ``points`` (k, 3) (m, world, in phase order) are solved one after the other
    from the centre posture, and at each the joint velocities for the path's velocity per
    unit phase ``velocities`` (k, 3) (m/rad) are those the tracker would command; the
    fastest joint sets the limit: Omega_max = ``joint_speed_limit`` (rad/s) / max |dq/dphi|.
    """
    q, fastest = posture.arm.copy(), 0.0
    for point, velocity in zip(np.asarray(points, dtype=float),
                               np.asarray(velocities, dtype=float)):
        q, _ = tracker.solve(q, point, max_iterations=100)
        fastest = max(fastest, float(np.max(np.abs(tracker.joint_velocity(q, velocity)))))
    return joint_speed_limit / fastest if fastest > 0 else float("inf")
