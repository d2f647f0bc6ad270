"""Executing a periodic movement model at any frequency, placed in front of the robot.

Where the movement goes: a model's positions are in the world frame of its demonstration.
:func:`place_model` moves it onto the table in front of the robot: the centre of the x-y
path's bounding box (the paper's demonstration-area centre, Fig. 3) is put at ``centre``
(x, y in m, world; adapt's ``--center``, by default the surface's wiping centre) and the
oscillation about it is scaled by ``amplitude_scale``. Goals move, weights stay: the DMP's
limit cycle is translated exactly (eqs. 6-7 are linear in g).
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import lru_cache

import numpy as np

from wipelab.errors import InputError
from wipelab.learning import PeriodicModel, default_width, fit_weights, limit_cycle

#: Phases (rad) on which a model's path is sampled for placement and checks.
PATH_PHASES = np.linspace(0.0, 2.0 * math.pi, 256, endpoint=False)
#: Phases per period in the table of a :class:`PathGenerator`.
TABLE_PHASES = 4096
#: Phases per kernel at which :func:`with_kernels` refits a waveform.
REFIT_SAMPLES_PER_KERNEL = 8
#: Relative smoothness penalty of that refit (see :func:`wipelab.learning.fit_weights`):
#: small, the waveform is exact data.
REFIT_SMOOTHING = 1e-8


def require_dofs(model: PeriodicModel, dofs, source: str) -> None:
    """InputError unless the model has all of ``dofs``."""
    missing = [d for d in dofs if d not in model.dofs]
    if missing:
        raise InputError(f"{source}: the model has DOFs {list(model.dofs)}; "
                         f"needs {', '.join(missing)}")


def dof_waveform(model: PeriodicModel, dofs, phases=PATH_PHASES, derivative: int = 0
                 ) -> np.ndarray:
    """Limit-cycle values (n, k) of the named DOFs at ``phases`` (phase derivatives if
    ``derivative`` > 0)."""
    index = [model.dofs.index(d) for d in dofs]
    return limit_cycle(phases, model.weights[index], model.goal[index], model.amplitude[index],
                       model.width, model.alpha_s, model.beta_s, derivative=derivative)


def path_centre(model: PeriodicModel) -> np.ndarray:
    """Centre (2,) of the bounding box of the model's x-y path (m)."""
    xy = dof_waveform(model, ("x", "y"))
    return 0.5 * (xy.min(axis=0) + xy.max(axis=0))


def with_kernels(model: PeriodicModel, n_kernels: int) -> PeriodicModel:
    """The model on ``n_kernels`` kernels of the default width (eq. 8), its limit cycle kept:
    the weights are refitted by least squares to the model's waveform at
    :data:`REFIT_SAMPLES_PER_KERNEL` phases per kernel (a smooth path moves by well under a
    micrometre; the refit error is reported by :func:`refit_error`)."""
    if n_kernels == model.kernels:
        return model
    phases = np.linspace(0.0, 2.0 * math.pi, REFIT_SAMPLES_PER_KERNEL * max(n_kernels,
                                                                            model.kernels),
                         endpoint=False)
    width = default_width(n_kernels)
    weights = fit_weights(phases, model.waveform(phases), model.goal, model.amplitude,
                          n_kernels, width, model.alpha_s, model.beta_s, smoothing=REFIT_SMOOTHING)
    return replace(model, kernels=int(n_kernels), width=width, weights=weights)


def refit_error(original: PeriodicModel, refitted: PeriodicModel, dofs) -> float:
    """Largest difference (m) between two models' waveforms of ``dofs`` along the path."""
    return float(np.max(np.abs(dof_waveform(original, dofs) - dof_waveform(refitted, dofs))))


#: Name of the DOF that holds how the learned height changes with the tempo (m per Hz).
TEMPO_DOF = "z_per_hz"


def with_height_profiles(model: PeriodicModel, profiles: dict[float, np.ndarray]
                         ) -> PeriodicModel:
    """The model with the learned height: DOF ``z`` at the model's (demonstrated) frequency
    and, when profiles at more than one tempo are given, DOF :data:`TEMPO_DOF` (m/Hz).

    Per phase, the heights learned at the tempos are fitted by a straight line in the
    frequency (a lag, tau, shifts a feature of the profile by Omega tau: to first order a
    change proportional to the frequency); ``z`` is the line at ``model.frequency_hz`` and
    :data:`TEMPO_DOF` its slope. Both are fitted onto the model's kernels (amplitude 1: the
    weights are in metres).

    Parameters
    ----------
    profiles : dict
        Frequency (Hz) -> heights (g,) (m, world z) at ``g`` phases evenly spaced from 0.
    """
    frequencies = np.array(sorted(profiles))
    heights = np.array([profiles[f] for f in frequencies])           # (tempos, g)
    if len(frequencies) > 1:
        slope, intercept = np.polyfit(frequencies - model.frequency_hz, heights, 1)
        waveforms = {"z": intercept, TEMPO_DOF: slope}
    else:
        waveforms = {"z": heights[0]}
    projection = _waveform_fit(heights.shape[1], model.kernels, model.width, model.alpha_s,
                               model.beta_s)
    base = _without(model, ("z", TEMPO_DOF))
    for name, waveform in waveforms.items():
        goal = float(np.mean(waveform))
        base = base.with_dof(name, projection @ (waveform - goal), goal, 1.0)
    return base


@lru_cache(maxsize=8)
def _waveform_fit(samples: int, n_kernels: int, width: float, alpha_s: float, beta_s: float
                  ) -> np.ndarray:
    """The linear map (N, samples) from a waveform minus its goal, at ``samples`` phases
    evenly spaced from 0, to the weights (amplitude 1) of
    :func:`wipelab.learning.fit_weights` (each column: the fit of one unit sample)."""
    phases = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
    unit = fit_weights(phases, np.eye(samples), np.zeros(samples), np.ones(samples), n_kernels,
                       width, alpha_s, beta_s, smoothing=REFIT_SMOOTHING)
    unit.setflags(write=False)
    return unit.T


def at_frequency(model: PeriodicModel, frequency_hz: float) -> PeriodicModel:
    """The model with ``z`` the height learned for ``frequency_hz`` (Hz): z + (frequency_hz -
    model.frequency_hz) z_per_hz, exact since the limit cycle is linear in weights and goal;
    without :data:`TEMPO_DOF`. A model without it is returned as it is."""
    if TEMPO_DOF not in model.dofs:
        return model
    z, slope = model.dofs.index("z"), model.dofs.index(TEMPO_DOF)
    if model.amplitude[z] != model.amplitude[slope]:
        raise ValueError(f"z and {TEMPO_DOF} must share their amplitude")
    delta = frequency_hz - model.frequency_hz
    weights, goal = model.weights.copy(), model.goal.copy()
    weights[z] += delta * weights[slope]
    goal[z] += delta * goal[slope]
    return _without(replace(model, weights=weights, goal=goal), (TEMPO_DOF,))


def _without(model: PeriodicModel, dofs) -> PeriodicModel:
    """The model without the named DOFs (those it has)."""
    keep = [i for i, d in enumerate(model.dofs) if d not in dofs]
    return replace(model, dofs=tuple(model.dofs[i] for i in keep), goal=model.goal[keep],
                   amplitude=model.amplitude[keep], weights=model.weights[keep])


def place_model(model: PeriodicModel, centre, amplitude_scale: float = 1.0) -> PeriodicModel:
    """The model with its x-y path scaled about its goal and centred at ``centre`` (2,)."""
    index = [model.dofs.index("x"), model.dofs.index("y")]
    amplitude = model.amplitude.copy()
    amplitude[index] *= amplitude_scale
    scaled = replace(model, amplitude=amplitude)
    goal = scaled.goal.copy()
    goal[index] += np.asarray(centre, dtype=float) - path_centre(scaled)
    return replace(scaled, goal=goal)


class PathGenerator:
    """Runs some DOFs of a model at a chosen frequency, sharing one phase.

    The output is the periodic DMP's steady state (its limit cycle, eqs. 6-7 solved in closed
    form by :func:`wipelab.learning.limit_cycle.limit_cycle`): started on it, integrating
    eqs. 6-7 gives exactly this, and the limit cycle does not depend on Omega, so a
    frequency change only changes how fast the phase runs. The limit cycle and its phase
    derivative are tabulated once, in one table, on :data:`TABLE_PHASES` phases per period
    and interpolated linearly (as the limit cycle's own basis is; error below a
    micrometre): one lookup per control period.

    Parameters
    ----------
    model : PeriodicModel
    dofs : sequence of str
        DOFs to run (e.g. ``("x", "y")`` or ``("x", "y", "z")``).
    phase : float
        Start phase (rad).
    """

    def __init__(self, model: PeriodicModel, dofs, phase: float = 0.0):
        self.model, self.dofs = model, tuple(dofs)
        self.phase = float(phase)
        grid = np.linspace(0.0, 2.0 * math.pi, TABLE_PHASES + 1)
        # rows: phase; then position and its phase derivative, each (d,)
        self._table = np.stack([dof_waveform(model, self.dofs, grid, derivative=k)
                                for k in range(2)], axis=1)

    def _lookup(self) -> np.ndarray:
        """Position and phase derivative (2, d) at the current phase."""
        where = (self.phase % (2.0 * math.pi)) * (TABLE_PHASES / (2.0 * math.pi))
        index = min(int(where), TABLE_PHASES - 1)
        fraction = where - index
        return self._table[index] * (1.0 - fraction) + self._table[index + 1] * fraction

    @property
    def position(self) -> np.ndarray:
        """Output (d,) (m) at the current phase."""
        return self._lookup()[0]

    def max_speed(self, omega: float) -> float:
        """Largest speed (m/s) of the output at Omega (rad/s)."""
        return float(np.max(np.linalg.norm(self._table[:, 1], axis=1))) * omega

    def step(self, omega: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Advance the phase by omega dt (rad/s, s); returns the position (d,) (m) and
        velocity (d,) (m/s) there (the joint servos' feed-forward)."""
        self.phase += omega * dt
        position, velocity = self._lookup()
        return position, velocity * omega
