"""The output dynamical system: a periodic DMP, eqs. 6-7, integrated in time.

Notation (per DOF): y position, s scaled velocity (y' = Omega s, eq. 7), g anchor (goal),
r amplitude, w_i weights, psi_i kernels of eq. 8, Omega frequency in rad/s, phi phase in rad.
"""

from __future__ import annotations

import numpy as np

from wipelab.learning.kernels import kernel_activations, normalised_forcing


def forcing_target(y, yd, ydd, omega, goal, alpha_s: float = 12.0, beta_s: float = 3.0):
    """The target of the forcing term (text after eq. 12).

    f_targ = ydd / Omega^2 - alpha_s (beta_s (g - y) - yd / Omega), from matching eqs. 6-7 to
    a demonstrated y with s = yd / Omega and s' = ydd / Omega.

    Parameters
    ----------
    y, yd, ydd : array, shape (..., d)
        Position (m), velocity (m/s) and acceleration (m/s^2) of the demonstration.
    omega : float or array broadcastable to (..., d)
        Frequency Omega in rad/s (> 0).
    goal : array, shape (d,) or broadcastable
        Anchor g (m).

    Returns
    -------
    f_targ : ndarray, shape (..., d), in metres (divide by r for the weights' scale).
    """
    y, yd, ydd = (np.asarray(a, dtype=np.float64) for a in (y, yd, ydd))
    return ydd / omega ** 2 - alpha_s * (beta_s * (goal - y) - yd / omega)


def max_phase_step(width: float) -> float:
    """Longest RK4 substep in phase (rad): half a kernel's std 1/sqrt(h), at most 0.25."""
    return min(0.25, 0.5 / np.sqrt(width))


def phase_substeps(phase_step: float, width: float) -> int:
    """Number of RK4 substeps for a phase increment (rad)."""
    return max(1, int(np.ceil(abs(phase_step) / max_phase_step(width))))


class PeriodicDMP:
    """Eqs. 6-7 for d DOFs sharing one phase and frequency.

    Integrated in the phase domain with classical RK4 (substeps of at most half a kernel
    width), so that any sample rate is stable and accurate: in time the system's poles sit at
    -6 Omega (alpha_s = 12, beta_s = 3), which explicit Euler at 30 Hz cannot follow at 3 Hz.

    Parameters
    ----------
    weights : ndarray, shape (d, N)
        w_i per DOF. Kept by reference, so an online learner may update it in place.
    goal, amplitude : ndarray, shape (d,)
        g and r per DOF (also plain attributes that may be changed between steps).
    width : float
        h of eq. 8.
    alpha_s, beta_s : float
        Gains of eq. 6.
    """

    def __init__(self, weights, goal, amplitude, width, alpha_s: float = 12.0, beta_s: float = 3.0):
        self.weights = np.asarray(weights, dtype=np.float64)
        if self.weights.ndim != 2:
            raise ValueError(f"weights must have shape (d, N), got {self.weights.shape}")
        n_dofs = self.weights.shape[0]
        self.goal = np.broadcast_to(np.asarray(goal, dtype=np.float64), (n_dofs,)).copy()
        self.amplitude = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), (n_dofs,)).copy()
        self.width = float(width)
        self.alpha_s = float(alpha_s)
        self.beta_s = float(beta_s)
        self.y_ = self.goal.copy()
        self.s_ = np.zeros(n_dofs)

    def reset(self, y, s) -> None:
        """Set the state: position y (d,) in m and scaled velocity s = yd / Omega (d,) in m/rad."""
        self.y_ = np.array(y, dtype=np.float64).reshape(self.goal.shape)
        self.s_ = np.array(s, dtype=np.float64).reshape(self.goal.shape)

    def _derivative(self, y, s, forcing):
        """(dy/dphi, ds/dphi) of eqs. 6-7 divided by Omega."""
        return s, self.alpha_s * (self.beta_s * (self.goal - y) - s) + self.amplitude * forcing

    def step(self, phase: float, omega: float, dt: float) -> np.ndarray:
        """Advance the state by dt with the phase running linearly from ``phase``.

        Parameters
        ----------
        phase : float
            Canonical phase at the start of the step (rad).
        omega : float
            Frequency Omega (rad/s) held over the step.
        dt : float
            Time step (s).

        Returns
        -------
        y : ndarray, shape (d,), the position at the end of the step (a copy).
        """
        phase_step = omega * dt
        n_sub = phase_substeps(phase_step, self.width)
        h = phase_step / n_sub
        phases = phase + 0.5 * h * np.arange(2 * n_sub + 1)
        forcing = normalised_forcing(kernel_activations(phases, self.weights.shape[1], self.width),
                                     self.weights)
        y, s = self.y_, self.s_
        for j in range(n_sub):
            f0, f_mid, f1 = forcing[2 * j], forcing[2 * j + 1], forcing[2 * j + 2]
            k1y, k1s = self._derivative(y, s, f0)
            k2y, k2s = self._derivative(y + 0.5 * h * k1y, s + 0.5 * h * k1s, f_mid)
            k3y, k3s = self._derivative(y + 0.5 * h * k2y, s + 0.5 * h * k2s, f_mid)
            k4y, k4s = self._derivative(y + h * k3y, s + h * k3s, f1)
            y = y + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)
            s = s + h / 6.0 * (k1s + 2.0 * k2s + 2.0 * k3s + k4s)
        self.y_, self.s_ = y, s
        return y.copy()
