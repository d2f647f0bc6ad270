"""Periodic movement learning: the two-layer system of Gams et al. (Humanoids 2010), Fig. 1.

Layer 1, the canonical system, extracts the fundamental frequency Omega and a phase phi from
the demonstration: the paper's pool of adaptive-frequency oscillators (eqs. 1-5,
:mod:`~wipelab.learning.afo`) or the adaptive Fourier series of Petric et al.
(:mod:`~wipelab.learning.afs`), started from the period that a fast detector finds after a
little more than two periods (:mod:`~wipelab.learning.period_detector`). Layer 2, the output
system, is a periodic DMP (eqs. 6-8, :mod:`~wipelab.learning.dmp`) whose weights are learned
online by incremental locally weighted regression (eqs. 13-15, :mod:`~wipelab.learning.lwr`)
or offline by regression over a whole recording (:mod:`~wipelab.learning.batch_fit`).

Notation (per DOF j; d DOFs, N kernels):
    y, yd, ydd   position (m), velocity (m/s), acceleration (m/s^2); world frame
    phi          canonical phase (rad); Omega = 2 pi frequency_hz (rad/s)
    g, r         anchor ("goal", m) and amplitude (m) of the DMP
    s            scaled velocity, yd = Omega s (eq. 7)
    psi_i        kernel i, exp(h (cos(phi - c_i) - 1)), c_i = 2 pi i / N (eq. 8)
    w            weights, shape (d, N)
    f_targ       the forcing term's target (text after eq. 12)
    alpha_s, beta_s = 12, 3 (eq. 6)

Only numpy and scipy (and numba for the online learner's per-sample loop) are imported here.
"""

from wipelab.learning.afo import AFOParameters
from wipelab.learning.afs import AFSParameters
from wipelab.learning.batch_fit import fit_weights
from wipelab.learning.dmp import forcing_target
from wipelab.learning.harmonic import (HarmonicFit, PeriodicityEstimate, fundamental_frequency_hz,
                                       harmonic_fit, locked_series, periodicity)
from wipelab.learning.kernels import default_width, kernel_activations, kernel_centres
from wipelab.learning.limit_cycle import limit_cycle, limit_cycle_basis
from wipelab.learning.lwr import IncrementalLWR
from wipelab.learning.model import MODEL_FORMAT, PeriodicModel
from wipelab.learning.offline import OfflineParameters, learn_offline
from wipelab.learning.online import (CANONICAL_SYSTEMS, LearnHistory, OnlineLearner,
                                     OnlineParameters, learn_online)
from wipelab.learning.period_detector import PeriodDetectorParameters
from wipelab.learning.sampling import to_uniform

__all__ = [
    "AFOParameters", "AFSParameters", "CANONICAL_SYSTEMS", "HarmonicFit", "IncrementalLWR", "LearnHistory", "MODEL_FORMAT",
    "OfflineParameters", "OnlineLearner", "OnlineParameters",
    "PeriodDetectorParameters", "PeriodicModel", "PeriodicityEstimate",
    "default_width", "fit_weights", "forcing_target", "fundamental_frequency_hz", "harmonic_fit",
    "kernel_activations", "kernel_centres", "learn_offline", "learn_online", "limit_cycle",
    "limit_cycle_basis", "locked_series", "periodicity", "to_uniform",
]
