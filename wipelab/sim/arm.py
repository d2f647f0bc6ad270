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

from dataclasses import dataclass

import numpy as np

from wipelab.sim.armar3 import RIGHT_ARM_JOINTS, TORSO_JOINTS, armar3b_urdf_path
from wipelab.sim.ik import ArmIK, IKParams
from wipelab.sim.kinematics import KinematicChain

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
SPEED_FRACTION = 0.85


@dataclass(frozen=True)
class TaskPosture:
    """Result of :meth:`RightArm.posture_for`."""

    torso: np.ndarray           # (3,) rad, held while wiping
    arm: np.ndarray             # (7,) rad at the centre, the rest posture of the tracker
    tcp_rotation: np.ndarray    # (3, 3) TCP orientation at the centre (R_ref of the grasp)
    error: float                # m: largest position error over the sample points
    margin: float               # rad: smallest distance of an arm joint from a limit


class RightArm:
    """Kinematics of torso + right arm for a robot whose platform stands at ``platform``
    (dict of platform joint values: x, y in m, yaw in rad)."""

    def __init__(self, platform: dict[str, float], ik: IKParams = IKParams()):
        self.urdf_text = armar3b_urdf_path().read_text()
        self.platform = dict(platform)
        self.ik_params = ik

    def _arm_ik(self, torso: np.ndarray, rest: np.ndarray) -> ArmIK:
        held = dict(self.platform)
        held.update(zip(TORSO_JOINTS, torso))
        chain = KinematicChain(self.urdf_text, "tcp_r", RIGHT_ARM_JOINTS, held=held)
        return ArmIK(chain, 0, rest, self.ik_params)

    def _evaluate(self, torso: np.ndarray, centre: np.ndarray, points: np.ndarray
                  ) -> TaskPosture:
        ik = self._arm_ik(torso, ARM_SEED)
        arm, error = ik.solve(ARM_SEED, centre, max_iterations=300)
        ik = self._arm_ik(torso, arm)
        margin = float(np.min(np.minimum(arm - ik.chain.lower, ik.chain.upper - arm)))
        for point in points:
            q, point_error = ik.solve(arm, point, max_iterations=150)
            error = max(error, point_error)
            margin = min(margin, float(np.min(np.minimum(q - ik.chain.lower,
                                                           ik.chain.upper - q))))
        return TaskPosture(torso, arm, ik.chain.forward(arm)[:3, :3], error, margin)

    def posture_for(self, centre, points) -> TaskPosture:
        """The posture for a task centred at ``centre`` (3,) that visits ``points`` (k, 3)
        (m, world): the least forward lean of the torso that reaches them all with
        :data:`LIMIT_MARGIN`; if none does, the one with the smallest error."""
        centre = np.asarray(centre, dtype=float)
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        best = None
        for pitch in HIP_PITCHES:
            posture = self._evaluate(np.array([pitch, 0.0, 0.0]), centre, points)
            if posture.error < REACH_TOLERANCE and posture.margin >= LIMIT_MARGIN:
                return posture
            if best is None or (posture.error, -posture.margin) < (best.error, -best.margin):
                best = posture
        return best

    def tracker(self, posture: TaskPosture) -> ArmIK:
        """IK on the 7 arm joints with the torso held at ``posture.torso``."""
        return self._arm_ik(posture.torso, posture.arm)


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
