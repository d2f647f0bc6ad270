"""Offline learning from a whole recording: frequency by least squares, weights by regression.

1. Fundamental frequency of all DOFs together, refined by least squares over the whole
   recording (:func:`wipelab.learning.harmonic.fundamental_frequency_hz`).
2. Phase phi(t) = 2 pi f t + phase_offset, with phase 0 where the reference DOF's fundamental
   peaks (the same convention as the online canonical systems).
3. Anchor g = the fitted offset and amplitude r = sqrt(2) x RMS of the fitted periodic part.
4. Weights by ridge regression of the positions on the DMP's limit cycle
   (:func:`wipelab.learning.batch_fit.fit_weights`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wipelab.learning.batch_fit import fit_weights
from wipelab.learning.harmonic import fundamental_frequency_hz
from wipelab.learning.kernels import default_width
from wipelab.learning.model import PeriodicModel
from wipelab.learning.online import LearnHistory


@dataclass(frozen=True)
class OfflineParameters:
    """Settings of the offline learner."""

    kernels: int = 25              # N
    width: float | None = None     # h of eq. 8; None -> 2.5 N
    alpha_s: float = 12.0          # eq. 6
    beta_s: float = 3.0            # eq. 6
    min_frequency_hz: float = 0.1  # search range of the fundamental (Hz)
    max_frequency_hz: float = 5.0

    @property
    def kernel_width(self) -> float:
        """h actually used."""
        return default_width(self.kernels) if self.width is None else float(self.width)


def learn_offline(t: np.ndarray, Y: np.ndarray, params: OfflineParameters = OfflineParameters(),
                  dofs=None, reference_dof: int = 0,
                  source: dict | None = None,
                  valid: np.ndarray | None = None) -> tuple[PeriodicModel, LearnHistory]:
    """Learn a periodic model from a whole recording at once.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times (s), uniform.
    Y : ndarray, shape (n, d)
        Positions (m).
    params : OfflineParameters
    dofs : sequence of str, optional
    reference_dof : int
        The DOF whose fundamental defines phase 0.
    source : dict, optional
    valid : ndarray of bool, shape (n,), optional
        Which samples were observed (default: all): the frequency, anchor, amplitude and
        weights are fitted to those only (see :func:`fundamental_frequency_hz`).

    Returns
    -------
    model, history : PeriodicModel, LearnHistory
    """
    t = np.asarray(t, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    n, d = Y.shape
    valid = np.ones(n, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    dofs = tuple(dofs) if dofs is not None else tuple(f"q{j}" for j in range(d))
    fit = fundamental_frequency_hz(t, Y, params.min_frequency_hz, params.max_frequency_hz,
                                   valid=valid)
    omega = 2.0 * math.pi * fit.frequency_hz
    a1, b1 = fit.coefficients[1, reference_dof], fit.coefficients[2, reference_dof]
    phase_offset = float(np.mod(-math.atan2(b1, a1), 2.0 * math.pi))
    phase = phase_offset + omega * t
    goal = fit.offset
    amplitude = np.where(fit.amplitude > 0.0, fit.amplitude, 1.0)
    width = params.kernel_width
    weights = fit_weights(phase[valid], Y[valid], goal, amplitude, params.kernels, width, params.alpha_s,
                          params.beta_s)
    model = PeriodicModel(frequency_hz=fit.frequency_hz, dofs=dofs, kernels=params.kernels,
                          width=width, alpha_s=params.alpha_s, beta_s=params.beta_s, goal=goal,
                          amplitude=amplitude, weights=weights, phase_offset=phase_offset,
                          source=source or {})
    history = LearnHistory(t=t, input=Y, output=model.waveform(phase), phase=phase,
                           fundamental_hz=np.full(n, fit.frequency_hz),
                           frequency_hz=np.full(n, fit.frequency_hz),
                           oscillators_hz=np.full((n, 1), fit.frequency_hz),
                           weights_t=t[-1:], weights=weights[None], valid=valid,
                           hand_overs=np.zeros(n, dtype=np.int64))
    return model, history
