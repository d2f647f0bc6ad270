"""Differential inverse kinematics for the 7-DOF arm (and the torso where reach needs it).

Weighted damped least squares with joint limits (numba kernels on the arrays of a
:class:`~wipelab.sim.kinematics.KinematicChain`; one iteration costs a few microseconds):

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

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from wipelab.linalg import solve_positive_definite
from wipelab.numba_cache import forget_stale_kernels
from wipelab.sim.kinematics import (KinematicChain, chain_forward, chain_jacobian,
                                    rotation_error)


@dataclass(frozen=True)
class IKParams:
    """Parameters of the differential IK."""

    damping: float = 0.01            # lambda (m): damped least squares, near singularities
    orientation_weight: float = 0.0  # m/rad: weight of the orientation error against position
    torso_cost: float = 25.0         # joint cost of a torso joint relative to an arm joint (1)
    limit_zone: float = 0.25         # rad: within this of a limit a joint's cost rises smoothly
    rest_gain: float = 0.3           # per iteration: pull toward the rest posture (null space)
    limit_margin: float = 0.02       # rad: joints are kept this far inside their limits
    max_step: float = 0.025          # rad: largest joint change per ``track`` (3 rad/s at 120 Hz)
    solve_step: float = 0.2          # rad: largest joint change per iteration of ``solve``
    iterations: int = 1              # iterations per call of ``track`` (resolved rate)
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
        self._position_only = (False, np.eye(3), params.orientation_weight, self.lower,
                               self.upper, self.cost, self.rest, params.limit_zone,
                               params.rest_gain, params.damping ** 2)

    def _kernel_arguments(self, rotation) -> tuple:
        if rotation is None:
            return self._position_only
        p = self.params
        return (p.orientation_weight > 0, np.asarray(rotation, dtype=float), p.orientation_weight,
                *self._position_only[3:])

    def track(self, q, position, tcp_velocity, rotation=None) -> tuple[np.ndarray, np.ndarray]:
        """One control period of resolved-rate tracking (one compiled call).

        Returns the joint targets (n,) moving the TCP from posture ``q`` toward ``position``
        (3,) (m, world) and, with weight, ``rotation`` (3, 3) (``params.iterations``
        iterations of at most ``params.max_step`` per joint), and the joint velocities (n,)
        (rad/s) that give the TCP velocity ``tcp_velocity`` (3,) (m/s, world) at those
        targets: the weighted damped least squares of one iteration without the null space
        (the servos' feed-forward).
        """
        return ik_track(*self.chain.arrays, np.asarray(q, dtype=float),
                        np.asarray(position, dtype=float), np.asarray(tcp_velocity, dtype=float),
                        *self._kernel_arguments(rotation), self.params.max_step,
                        self.params.iterations)

    def joint_velocity(self, q, tcp_velocity) -> np.ndarray:
        """Joint velocities (n,) (rad/s) that give the TCP velocity ``tcp_velocity`` (3,) (m/s)
        at posture ``q``: the feed-forward :meth:`track` sends to the servos."""
        return ik_velocity(*self.chain.arrays, np.asarray(q, dtype=float),
                           np.asarray(tcp_velocity, dtype=float), self.lower, self.upper,
                           self.cost, self.params.limit_zone, self.params.damping ** 2)

    def solve(self, q, position, rotation=None, max_iterations: int = 200
              ) -> tuple[np.ndarray, float]:
        """Iterate until the position error is below ``tolerance``; returns (q, error m)."""
        q, error = ik_solve(*self.chain.arrays, np.asarray(q, dtype=float),
                            np.asarray(position, dtype=float), *self._kernel_arguments(rotation),
                            self.params.solve_step, self.params.tolerance, max_iterations)
        return q, float(error)


# -- compiled kernels (numba) -----------------------------------------------------------------

@njit(cache=True)
def _inverse_costs(q, lower, upper, cost, limit_zone) -> np.ndarray:
    """W^-1 (n,): each joint's inverse cost, rising smoothly to its limits."""
    inv_cost = np.empty(q.size)
    for j in range(q.size):
        distance = max(min(q[j] - lower[j], upper[j] - q[j]), 1e-3)
        inv_cost[j] = 1.0 / (cost[j] * (1.0 + (limit_zone / distance) ** 2))
    return inv_cost


@njit(cache=True)
def _weighted_solution(rows, weighted, rhs, damping2) -> np.ndarray:
    """W^-1 J^T (J W^-1 J^T + lambda^2 I)^-1 rhs with ``weighted`` = J W^-1 (m, n).

    The m x m system (m <= 6, symmetric positive definite for lambda > 0; its lower triangle
    is built) is solved by :func:`wipelab.linalg.solve_positive_definite` in plain loops: at
    this size a LAPACK/BLAS call costs more than the arithmetic.
    """
    m, n = rows.shape
    gram = np.empty((m, m))
    for a in range(m):
        for b in range(a + 1):
            total = 0.0
            for j in range(n):
                total += weighted[a, j] * rows[b, j]
            gram[a, b] = total
        gram[a, a] += damping2
    solution = solve_positive_definite(gram, rhs.reshape((m, 1)))[:, 0]
    dq = np.zeros(n)
    for r in range(m):
        for j in range(n):
            dq[j] += solution[r] * weighted[r, j]
    return dq


@njit(cache=True)
def ik_velocity(before, axes, prismatic, tail, q, tcp_velocity, lower, upper, cost, limit_zone,
                damping2) -> np.ndarray:
    """Joint velocities (n,) for a TCP velocity (3,) at ``q``: W^-1 J^T (J W^-1 J^T +
    lambda^2 I)^-1 v with the position rows of J (see :meth:`ArmIK.track`)."""
    jac = np.empty((6, q.size))
    chain_jacobian(before, axes, prismatic, tail, q, jac)
    rows = np.ascontiguousarray(jac[:3])
    weighted = rows * _inverse_costs(q, lower, upper, cost, limit_zone)
    return _weighted_solution(rows, weighted, tcp_velocity, damping2)


@njit(cache=True)
def ik_iterate(before, axes, prismatic, tail, q, position, use_rotation, rotation,
               orientation_weight, lower, upper, cost, rest, limit_zone, rest_gain, damping2,
               max_step) -> np.ndarray:
    """One iteration of the weighted damped least squares of the module docstring.

    The chain is :attr:`KinematicChain.arrays`; ``q``, ``lower``, ``upper``, ``cost``,
    ``rest`` (n,); ``position`` (3,) m; ``rotation`` (3, 3), used if ``use_rotation``;
    ``damping2`` = lambda^2. Returns the new joint values (n,), inside the limits.
    """
    n = q.size
    jac = np.empty((6, n))
    pose = chain_jacobian(before, axes, prismatic, tail, q, jac)
    m = 6 if use_rotation else 3
    error = np.empty(m)
    rows = np.empty((m, n))
    for r in range(3):
        error[r] = position[r] - pose[r, 3]
        rows[r] = jac[r]
    if use_rotation:
        turn = rotation_error(np.ascontiguousarray(pose[:3, :3]), rotation)
        for r in range(3):
            error[3 + r] = orientation_weight * turn[r]
            rows[3 + r] = orientation_weight * jac[3 + r]
    inv_cost = _inverse_costs(q, lower, upper, cost, limit_zone)
    free = np.ones(n)
    posture = rest_gain * (rest - q)
    candidate = q.copy()
    for _ in range(3):
        weighted = rows * (inv_cost * free)
        free_posture = posture * free
        rhs = error.copy()
        for r in range(m):
            for j in range(n):
                rhs[r] -= rows[r, j] * free_posture[j]
        dq = _weighted_solution(rows, weighted, rhs, damping2) + free_posture
        scale = np.max(np.abs(dq)) / max_step
        if scale > 1.0:
            dq /= scale
        candidate = q + dq
        hit = False
        for j in range(n):
            if free[j] > 0 and (candidate[j] < lower[j] or candidate[j] > upper[j]):
                free[j] = 0.0
                hit = True
        if not hit:
            break
    return np.minimum(np.maximum(candidate, lower), upper)


@njit(cache=True)
def ik_track(before, axes, prismatic, tail, q, position, tcp_velocity, use_rotation, rotation,
             orientation_weight, lower, upper, cost, rest, limit_zone, rest_gain, damping2,
             max_step, iterations) -> tuple[np.ndarray, np.ndarray]:
    """``iterations`` of :func:`ik_iterate`, then :func:`ik_velocity` at the result (see
    :meth:`ArmIK.track`); returns (q, joint velocities)."""
    for _ in range(iterations):
        q = ik_iterate(before, axes, prismatic, tail, q, position, use_rotation, rotation,
                       orientation_weight, lower, upper, cost, rest, limit_zone, rest_gain,
                       damping2, max_step)
    return q, ik_velocity(before, axes, prismatic, tail, q, tcp_velocity, lower, upper, cost,
                          limit_zone, damping2)


@njit(cache=True)
def ik_solve(before, axes, prismatic, tail, q, position, use_rotation, rotation,
             orientation_weight, lower, upper, cost, rest, limit_zone, rest_gain, damping2,
             max_step, tolerance, max_iterations) -> tuple[np.ndarray, float]:
    """:func:`ik_iterate` until the position error (m) is below ``tolerance`` or
    ``max_iterations``; returns (q, error)."""
    error = np.inf
    for _ in range(max_iterations):
        q = ik_iterate(before, axes, prismatic, tail, q, position, use_rotation, rotation,
                       orientation_weight, lower, upper, cost, rest, limit_zone, rest_gain,
                       damping2, max_step)
        tip = chain_forward(before, axes, prismatic, tail, q)
        error = math.sqrt((position[0] - tip[0, 3]) ** 2 + (position[1] - tip[1, 3]) ** 2
                          + (position[2] - tip[2, 3]) ** 2)
        if error < tolerance:
            break
    return q, error


forget_stale_kernels(__name__)
