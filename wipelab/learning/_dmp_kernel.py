"""The periodic DMP's integration step compiled with numba (twin of PeriodicDMP.step)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


@njit(cache=True)
def forcing(phase, weights, width, centres, out):
    """Normalised forcing sum psi w / sum psi at one phase, per DOF, into out (d,)."""
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
    """RK4 in phase with substeps, as PeriodicDMP.step."""
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
            k1s = alpha_s * (beta_s * (g - y0) - s0) + r * f0[d]
            y1, s1 = y0 + 0.5 * h * k1y, s0 + 0.5 * h * k1s
            k2y = s1
            k2s = alpha_s * (beta_s * (g - y1) - s1) + r * f_mid[d]
            y2, s2 = y0 + 0.5 * h * k2y, s0 + 0.5 * h * k2s
            k3y = s2
            k3s = alpha_s * (beta_s * (g - y2) - s2) + r * f_mid[d]
            y3, s3 = y0 + h * k3y, s0 + h * k3s
            k4y = s3
            k4s = alpha_s * (beta_s * (g - y3) - s3) + r * f1[d]
            y[d] = y0 + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)
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
