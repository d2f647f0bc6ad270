"""The learned periodic movement: a periodic DMP with its frequency and phase, as model.json.

JSON format ``wipelab.periodic_dmp/1`` (DESIGN.md), keys sorted, plain lists::

    format        "wipelab.periodic_dmp/1"
    frequency_hz  fundamental frequency Omega / 2 pi
    dofs          DOF names, e.g. ["x", "y"] (world frame, metres)
    kernels       N;  width: h;  alpha_s, beta_s: gains of eq. 6
    goal          g per DOF (m);  amplitude: r per DOF (m);  weights: d lists of N
    phase_offset  canonical phase at t = 0 of the input (rad): phi(t) = phase_offset + Omega t
    source        where it came from (input file hash, stage parameters)
    surface       null, or the surface an adapted DOF was learned on
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from wipelab.learning.dmp import max_phase_step, rollout
from wipelab.learning.kernels import kernel_centres
from wipelab.learning.limit_cycle import limit_cycle

MODEL_FORMAT = "wipelab.periodic_dmp/1"

_FIELDS = ("frequency_hz", "dofs", "kernels", "width", "alpha_s", "beta_s", "goal", "amplitude",
           "weights", "phase_offset", "source")


@dataclass(frozen=True)
class PeriodicModel:
    """A periodic DMP (eqs. 6-8) with the frequency and phase it was learned at.

    Attributes
    ----------
    frequency_hz : float
        Fundamental frequency (Hz).
    dofs : tuple of str
        DOF names, d of them.
    kernels : int
        N.
    width : float
        h of eq. 8.
    alpha_s, beta_s : float
        Gains of eq. 6.
    goal : ndarray, shape (d,)
        Anchor g per DOF (m, world frame).
    amplitude : ndarray, shape (d,)
        Amplitude r per DOF (m).
    weights : ndarray, shape (d, N)
        w per DOF.
    phase_offset : float
        Canonical phase at t = 0 of the input (rad), so that a rollout lines up with it.
    source : dict
        Provenance: input file hash, stage parameters.
    surface : dict or None
        Set by adapt: the surface the extra DOF was learned on.
    """

    frequency_hz: float
    dofs: tuple[str, ...]
    kernels: int
    width: float
    alpha_s: float
    beta_s: float
    goal: np.ndarray
    amplitude: np.ndarray
    weights: np.ndarray
    phase_offset: float
    source: dict = field(default_factory=dict)
    surface: dict | None = None

    def __post_init__(self):
        d = len(self.dofs)
        checks = [
            (math.isfinite(self.frequency_hz) and self.frequency_hz > 0, "frequency_hz must be > 0"),
            (d > 0 and len(set(self.dofs)) == d, "dofs must be distinct names"),
            (int(self.kernels) == self.kernels and self.kernels > 0, "kernels must be a positive integer"),
            (math.isfinite(self.width) and self.width > 0, "width must be > 0"),
            (self.alpha_s > 0 and self.beta_s > 0, "alpha_s and beta_s must be > 0"),
            (math.isfinite(self.phase_offset), "phase_offset must be finite"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(f"{MODEL_FORMAT}: {message}")
        for name, shape in (("goal", (d,)), ("amplitude", (d,)), ("weights", (d, self.kernels))):
            value = np.array(getattr(self, name), dtype=np.float64)
            if value.shape != shape:
                raise ValueError(f"{MODEL_FORMAT}: {name} must have shape {shape} "
                                 f"(dofs x kernels), got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{MODEL_FORMAT}: {name} holds NaN or inf")
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "dofs", tuple(str(name) for name in self.dofs))
        object.__setattr__(self, "kernels", int(self.kernels))

    @property
    def omega(self) -> float:
        """Omega in rad/s."""
        return 2.0 * math.pi * self.frequency_hz

    def to_dict(self) -> dict:
        """The JSON object of model.json (plain Python types)."""
        return {
            "format": MODEL_FORMAT,
            "frequency_hz": float(self.frequency_hz),
            "dofs": list(self.dofs),
            "kernels": self.kernels,
            "width": float(self.width),
            "alpha_s": float(self.alpha_s),
            "beta_s": float(self.beta_s),
            "goal": self.goal.tolist(),
            "amplitude": self.amplitude.tolist(),
            "weights": self.weights.tolist(),
            "phase_offset": float(self.phase_offset),
            "source": self.source,
            "surface": self.surface,
        }

    @classmethod
    def from_dict(cls, data) -> PeriodicModel:
        """Build from a model.json object; ValueError with a clear message if it is not one."""
        if not isinstance(data, dict):
            raise ValueError(f"not a {MODEL_FORMAT} model (expected a JSON object)")
        if data.get("format") != MODEL_FORMAT:
            raise ValueError(f"format is {data.get('format')!r}, expected {MODEL_FORMAT!r}")
        missing = [key for key in _FIELDS if key not in data]
        if missing:
            raise ValueError(f"{MODEL_FORMAT}: missing key(s) {', '.join(missing)}")
        try:
            return cls(
                frequency_hz=float(data["frequency_hz"]), dofs=tuple(data["dofs"]),
                kernels=data["kernels"], width=float(data["width"]),
                alpha_s=float(data["alpha_s"]), beta_s=float(data["beta_s"]),
                goal=data["goal"], amplitude=data["amplitude"], weights=data["weights"],
                phase_offset=float(data["phase_offset"]), source=dict(data["source"]),
                surface=data.get("surface"))
        except (TypeError, ValueError) as error:
            raise ValueError(str(error) if str(error).startswith(MODEL_FORMAT)
                             else f"{MODEL_FORMAT}: {error}") from None

    def waveform(self, phase) -> np.ndarray:
        """The limit-cycle output at phases ``phase`` (rad), shape (n, d); independent of Omega."""
        return limit_cycle(phase, self.weights, self.goal, self.amplitude, self.width,
                           self.alpha_s, self.beta_s)

    def rollout(self, duration_s: float, rate_hz: float, frequency_hz: float | None = None,
                amplitude=None, goal=None) -> tuple[np.ndarray, np.ndarray]:
        """Integrate eqs. 6-7 from the limit cycle (no start-up transient).

        The RK4 phase-domain integration of :func:`~wipelab.learning.dmp.dmp_step`.

        Parameters
        ----------
        duration_s : float
            Length (s); samples at t = k / rate_hz for t < duration_s.
        rate_hz : float
            Output sample rate (Hz).
        frequency_hz : float, optional
            Modulated frequency Omega / 2 pi (default: the learned one).
        amplitude, goal : array, shape (d,), optional
            Modulated r (m) and anchor g (m) (default: the learned ones).

        Returns
        -------
        t : ndarray, shape (n,)
            Time (s), phi(t) = phase_offset + 2 pi frequency_hz t.
        y : ndarray, shape (n, d)
            Positions (m).
        """
        if not (duration_s > 0 and rate_hz > 0):
            raise ValueError("duration_s and rate_hz must be > 0")
        frequency_hz = self.frequency_hz if frequency_hz is None else float(frequency_hz)
        if not frequency_hz > 0:
            raise ValueError("frequency_hz must be > 0")
        amplitude = self.amplitude if amplitude is None else np.asarray(amplitude, dtype=np.float64)
        goal = self.goal if goal is None else np.asarray(goal, dtype=np.float64)
        dt = 1.0 / rate_hz
        t = np.arange(int(math.ceil(duration_s * rate_hz - 1e-9))) * dt
        omega = 2.0 * math.pi * frequency_hz
        start = [self.phase_offset]
        y0 = limit_cycle(start, self.weights, goal, amplitude, self.width, self.alpha_s, self.beta_s)
        s0 = limit_cycle(start, self.weights, goal, amplitude, self.width, self.alpha_s,
                         self.beta_s, derivative=1)
        y = np.empty((t.size, len(self.dofs)))
        rollout(y0[0].copy(), s0[0].copy(), np.array(goal, dtype=np.float64),
                np.array(amplitude, dtype=np.float64), np.ascontiguousarray(self.weights),
                self.width, kernel_centres(self.kernels), self.alpha_s, self.beta_s,
                self.phase_offset, omega, dt, max_phase_step(self.width), y)
        return t, y

    def with_dof(self, name: str, weights, goal: float, amplitude: float) -> PeriodicModel:
        """A copy with DOF ``name`` added (or replaced): weights (N,), goal g (m), amplitude r (m)."""
        dofs = list(self.dofs)
        all_weights = [np.asarray(row) for row in self.weights]
        goals, amplitudes = list(self.goal), list(self.amplitude)
        index = dofs.index(name) if name in dofs else len(dofs)
        if index == len(dofs):
            dofs.append(name)
            all_weights.append(None)
            goals.append(None)
            amplitudes.append(None)
        all_weights[index] = np.asarray(weights, dtype=np.float64).reshape(self.kernels)
        goals[index], amplitudes[index] = float(goal), float(amplitude)
        return replace(self, dofs=tuple(dofs), weights=np.vstack(all_weights),
                       goal=np.array(goals), amplitude=np.array(amplitudes))
