"""Velocity-resolved active compliance in z, eqs. 9-12 (pure numpy).

With S_v = 0, K_F = diag(0, 0, k_F, 0, 0, 0) and S_F = diag(0, 0, 1, 0, 0, 0), eq. 9 gives the
commanded z velocity from the measured force and eq. 10 integrates it onto the reference:

    z' = k_F (F - F_0)                    (11)
    z  = z_r + sum z' dt                  (10, 12)

F is the force the environment exerts on the tool along world +z (``feedback="fz"``) or the
length of the force vector (``feedback="norm"``, Sec. II-B: the hand then also moves up when
it hits something from the side, e.g. the edge of a sink). Without contact F = 0 and the
tool moves down at k_F F_0 (capped), until it presses with F_0.

Two additions of the paper: a dead zone of response around F_0 (|F - F_0| below
``dead_zone`` gives no motion; outside it the response is shifted so that it starts from 0:
continuous, no chattering at the boundary), and a cap of the force feedback at
``max_speed``. A safety limit on |F| stops the movement (:func:`safety_tripped`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Accepted values of ``feedback``.
FEEDBACK_MODES = ("fz", "norm")


@dataclass(frozen=True)
class ComplianceParams:
    """Parameters of eqs. 9-12."""

    force_gain: float = 0.02      # k_F in m/(N s): the paper's 20 with positions in mm
    target_force: float = 10.0    # F_0 in N: how hard the sponge presses on the surface
    dead_zone: float = 1.0        # N: no response while |F - F_0| is below this
    max_speed: float = 0.12       # m/s: cap of the force feedback velocity (the paper's 120 mm/s)
    feedback: str = "fz"          # "fz" (F_z) or "norm" (|F|), see the module docstring
    safety_force: float = 60.0    # N: |F| above this stops the movement

    def __post_init__(self):
        if self.feedback not in FEEDBACK_MODES:
            raise ValueError(f"feedback must be one of {', '.join(FEEDBACK_MODES)}, "
                             f"got {self.feedback!r}")
        if not (self.force_gain > 0 and self.max_speed > 0 and self.dead_zone >= 0):
            raise ValueError("force_gain and max_speed must be > 0, dead_zone >= 0")
        if not 0 < self.target_force < self.safety_force:
            raise ValueError(f"target force must be in (0, {self.safety_force:g}) N "
                             f"(the safety limit), got {self.target_force:g}")


def feedback_force(force: np.ndarray, mode: str) -> float:
    """The scalar F of eq. 11 from the contact force (3,) (N, world): F_z or |F|."""
    fx, fy, fz = np.asarray(force, dtype=float).tolist()
    return fz if mode == "fz" else math.sqrt(fx * fx + fy * fy + fz * fz)


def dead_zone(error: float, width: float) -> float:
    """Shifted dead zone: 0 inside [-width, width], error -/+ width outside."""
    return math.copysign(max(abs(error) - width, 0.0), error)


def compliance_velocity(force: np.ndarray, params: ComplianceParams) -> float:
    """Eq. 11 with dead zone and cap: commanded z velocity (m/s, world +z up).

    Parameters
    ----------
    force : array, shape (3,)
        Force the environment exerts on the tool (N, world frame).
    """
    error = feedback_force(force, params.feedback) - params.target_force
    velocity = params.force_gain * dead_zone(error, params.dead_zone)
    return min(max(velocity, -params.max_speed), params.max_speed)


def safety_tripped(force: np.ndarray, params: ComplianceParams) -> bool:
    """True when |F| (N) exceeds the safety limit: the movement must stop."""
    return feedback_force(force, "norm") > params.safety_force


class ComplianceIntegrator:
    """Eq. 10 in z: the offset sum z' dt that active compliance adds to the reference z_r.

    Attributes
    ----------
    offset_ : float
        Current integral (m).
    velocity_ : float
        Last commanded z' (m/s).
    """

    def __init__(self, params: ComplianceParams, offset: float = 0.0):
        self.params = params
        self.offset_ = float(offset)
        self.velocity_ = 0.0

    def update(self, force: np.ndarray, dt: float) -> float:
        """Integrate one control period (eq. 12); returns the new offset (m)."""
        self.velocity_ = compliance_velocity(force, self.params)
        self.offset_ += self.velocity_ * dt
        return self.offset_
