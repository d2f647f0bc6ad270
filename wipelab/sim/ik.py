"""Differential inverse kinematics for the 7-DOF arm (and the torso where reach needs it).

Weighted damped least squares with joint limits (pure numpy, driven by
:class:`~wipelab.sim.kinematics.KinematicChain`):

    dq = W^-1 J^T (J W^-1 J^T + lambda^2 I)^-1 e  +  (I - J^+ J) k_rest (q_rest - q)

where e stacks the TCP position error (m) and, weighted by ``orientation_weight`` (m/rad),
the orientation error (rad); W holds each joint's cost: the torso is expensive (it moves only
when the arm alone cannot reach) and a joint's cost rises smoothly as it nears a limit
(1 + (zone / distance)^2), so that the solution bends away from limits without jumps; the
null-space term pulls toward a rest posture, which makes the solution along a periodic path
periodic too. A joint that would still cross a limit is frozen for the rest of the step and
the step is solved again without it; each step is capped at ``max_step`` per joint (a joint
velocity limit), so the commanded motion stays smooth.

The TCP's orientation is not controlled tightly (the paper controls the position of the tool
in task space); with ``orientation_weight`` small the hand orientation follows the arm, and
with an unknown grasp this changes the height at which the sponge touches a flat table along
the path (the paper's Fig. 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wipelab.sim.kinematics import KinematicChain, rotation_error


@dataclass(frozen=True)
class IKParams:
    """Parameters of the differential IK."""

    damping: float = 0.01            # lambda (m): damped least squares, near singularities
    orientation_weight: float = 0.0  # m/rad: weight of the orientation error against position
    torso_cost: float = 25.0         # joint cost of a torso joint relative to an arm joint (1)
    limit_zone: float = 0.25         # rad: within this of a limit a joint's cost rises smoothly
    rest_gain: float = 0.3           # per iteration: pull toward the rest posture (null space)
    limit_margin: float = 0.02       # rad: joints are kept this far inside their limits
    max_step: float = 0.025          # rad: largest joint change per ``step`` (3 rad/s at 120 Hz)
    solve_step: float = 0.2          # rad: largest joint change per iteration of ``solve``
    iterations: int = 1              # iterations per call of ``step`` (resolved rate)
    tolerance: float = 1e-3          # m: position error counted as "reached" by ``solve``


class ArmIK:
    """Differential IK on a :class:`KinematicChain` whose active joints are torso + arm.

    Parameters
    ----------
    chain : KinematicChain
        Active joints in q order; the first ``n_torso`` of them are torso joints.
    n_torso : int
        How many leading joints are torso joints (cost ``torso_cost``).
    rest : array, shape (n,)
        Rest posture (rad).
    params : IKParams
    """

    def __init__(self, chain: KinematicChain, n_torso: int, rest, params: IKParams = IKParams()):
        self.chain = chain
        self.params = params
        n = len(chain.active)
        self.cost = np.ones(n)
        self.cost[:n_torso] = params.torso_cost
        self.lower = chain.lower + params.limit_margin
        self.upper = chain.upper - params.limit_margin
        self.rest = np.clip(np.asarray(rest, dtype=float), self.lower, self.upper)
        self._damping = params.damping ** 2 * np.eye(6)

    def _iterate(self, q: np.ndarray, position: np.ndarray, rotation: np.ndarray | None,
                 max_step: float) -> np.ndarray:
        pose, jac = self.chain.jacobian(q)
        p = self.params
        error = position - pose[:3, 3]
        rows = jac[:3]
        if rotation is not None and p.orientation_weight > 0:
            error = np.concatenate([error, p.orientation_weight
                                    * rotation_error(pose[:3, :3], rotation)])
            rows = np.vstack([rows, p.orientation_weight * jac[3:]])
        distance = np.maximum(np.minimum(q - self.lower, self.upper - q), 1e-3)
        inv_cost = 1.0 / (self.cost * (1.0 + (p.limit_zone / distance) ** 2))
        free = np.ones(q.size)
        posture = p.rest_gain * (self.rest - q)
        damping = self._damping[:rows.shape[0], :rows.shape[0]]
        for _ in range(3):
            jw = rows * (inv_cost * free)
            pinv = jw.T @ np.linalg.inv(jw @ rows.T + damping)
            free_posture = posture * free
            dq = pinv @ (error - rows @ free_posture) + free_posture
            scale = np.max(np.abs(dq)) / max_step
            if scale > 1.0:
                dq /= scale
            candidate = q + dq
            hit = (free > 0) & ((candidate < self.lower) | (candidate > self.upper))
            if not hit.any():
                break
            free[hit] = 0.0
        return np.clip(candidate, self.lower, self.upper)

    def step(self, q, position, rotation=None) -> np.ndarray:
        """Joint targets (n,) moving the TCP from posture ``q`` toward ``position`` (3,) (m,
        world) and, with weight, ``rotation`` (3, 3); ``params.iterations`` iterations of at
        most ``params.max_step`` per joint."""
        q = np.asarray(q, dtype=float)
        position = np.asarray(position, dtype=float)
        for _ in range(self.params.iterations):
            q = self._iterate(q, position, rotation, self.params.max_step)
        return q

    def solve(self, q, position, rotation=None, max_iterations: int = 200
              ) -> tuple[np.ndarray, float]:
        """Iterate until the position error is below ``tolerance``; returns (q, error m)."""
        q = np.asarray(q, dtype=float)
        position = np.asarray(position, dtype=float)
        error = np.inf
        for _ in range(max_iterations):
            q = self._iterate(q, position, rotation, self.params.solve_step)
            error = float(np.linalg.norm(position - self.chain.forward(q)[:3, 3]))
            if error < self.params.tolerance:
                break
        return q, error
