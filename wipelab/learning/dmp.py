"""The output dynamical system: a periodic DMP, eqs. 6-7, integrated in time (compiled).

Notation (per DOF): y position, s scaled velocity (y' = Omega s, eq. 7), g anchor (goal),
r amplitude, w_i weights, psi_i kernels of eq. 8, Omega frequency in rad/s, phi phase in rad.

Integrated in the phase domain with classical RK4 (substeps of at most half a kernel width,
:func:`max_phase_step`), so that any sample rate is stable and accurate: in time the
system's poles sit at -6 Omega (alpha_s = 12, beta_s = 3), which explicit Euler at 30 Hz
cannot follow at 3 Hz. :func:`dmp_step` is the one integrator: the online learner's kernel
and :meth:`~wipelab.learning.model.PeriodicModel.rollout` (through :func:`rollout`) call it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


@njit(cache=True)
def forcing_target(y, yd, ydd, omega, goal, alpha_s: float = 12.0, beta_s: float = 3.0):
    """The target of the forcing term (text after eq. 12).

    f_targ = ydd / Omega^2 - alpha_s (beta_s (g - y) - yd / Omega), from matching eqs. 6-7 to
    a demonstrated y with s = yd / Omega and s' = ydd / Omega.

    Parameters
    ----------
    y, yd, ydd : float or ndarray, shape (..., d)
        Position (m), velocity (m/s) and acceleration (m/s^2) of the demonstration.
    omega : float
        Frequency Omega in rad/s (> 0).
    goal : float or ndarray, shape (d,)
        Anchor g (m).

    Returns
    -------
    f_targ : float or ndarray like y, in metres (divide by r for the weights' scale).
    """
    return ydd / omega ** 2 - alpha_s * (beta_s * (goal - y) - yd / omega)


def max_phase_step(width: float) -> float:
    """Longest RK4 substep in phase (rad): half a kernel's std 1/sqrt(h), at most 0.25."""
    return min(0.25, 0.5 / math.sqrt(width))


@njit(cache=True)
def forcing(phase, weights, width, centres, out):
    """Normalised forcing sum psi_i w_i / sum psi_i of eq. 6 (kernels of eq. 8) at one phase,
    per DOF, into out (d,)."""
    total = 0.0
    out[:] = 0.0
    for i in range(centres.shape[0]):
        psi = math.exp(width * (math.cos(phase - centres[i]) - 1.0))
        total += psi
        for d in range(out.shape[0]):
            out[d] += psi * weights[d, i]
    for d in range(out.shape[0]):
        out[d] /= total


@njit(cache=True)
def dmp_step(y, s, goal, amplitude, weights, width, centres, alpha_s, beta_s, phase, omega, dt,
             max_phase_step, f0, f_mid, f1):
    """Advance eqs. 6-7 by dt with the phase running linearly from ``phase`` at Omega, in place.

    Parameters
    ----------
    y, s : ndarray, shape (d,)
        Position (m) and scaled velocity s = yd / Omega (m/rad), updated.
    goal, amplitude : ndarray, shape (d,)
        g and r (m).
    weights : ndarray, shape (d, N)
    width : float
        h of eq. 8.
    centres : ndarray, shape (N,)
        Kernel centres c_i (rad).
    alpha_s, beta_s : float
        Gains of eq. 6.
    phase, omega, dt : float
        Phase at the start of the step (rad), Omega held over it (rad/s), time step (s).
    max_phase_step : float
        Longest RK4 substep in phase (rad), see :func:`max_phase_step`.
    f0, f_mid, f1 : ndarray, shape (d,)
        Scratch.
    """
    phase_step = omega * dt
    n_sub = max(1, int(math.ceil(abs(phase_step) / max_phase_step)))
    h = phase_step / n_sub
    forcing(phase, weights, width, centres, f1)
    for j in range(n_sub):
        start = phase + h * j
        f0[:] = f1                                   # the previous substep's end
        forcing(start + 0.5 * h, weights, width, centres, f_mid)
        forcing(start + h, weights, width, centres, f1)
        for d in range(y.shape[0]):
            g, r = goal[d], amplitude[d]
            y0, s0 = y[d], s[d]
            k1y = s0
            k1s = alpha_s * (beta_s * (g - y0) - s0) + r * f0[d]                     # eq. 6
            y1, s1 = y0 + 0.5 * h * k1y, s0 + 0.5 * h * k1s
            k2y = s1
            k2s = alpha_s * (beta_s * (g - y1) - s1) + r * f_mid[d]
            y2, s2 = y0 + 0.5 * h * k2y, s0 + 0.5 * h * k2s
            k3y = s2
            k3s = alpha_s * (beta_s * (g - y2) - s2) + r * f_mid[d]
            y3, s3 = y0 + h * k3y, s0 + h * k3s
            k4y = s3
            k4s = alpha_s * (beta_s * (g - y3) - s3) + r * f1[d]
            y[d] = y0 + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)              # eq. 7
            s[d] = s0 + h / 6.0 * (k1s + 2.0 * k2s + 2.0 * k3s + k4s)


@njit(cache=True)
def rollout(y, s, goal, amplitude, weights, width, centres, alpha_s, beta_s, start_phase, omega,
            dt, max_phase_step, out):
    """Integrate from state (y, s) at start_phase; out[0] = y, out[k] after k steps of dt."""
    n_dofs = y.shape[0]
    f0 = np.empty(n_dofs)
    f_mid = np.empty(n_dofs)
    f1 = np.empty(n_dofs)
    out[0] = y
    for k in range(1, out.shape[0]):
        dmp_step(y, s, goal, amplitude, weights, width, centres, alpha_s, beta_s,
                 start_phase + omega * dt * (k - 1), omega, dt, max_phase_step, f0, f_mid, f1)
        out[k] = y


forget_stale_kernels(__name__)
