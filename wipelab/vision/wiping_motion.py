"""Human-like wiping motion of a sponge on a table: the ground truth that synth renders.

A pattern (circle, line, figure-eight) in the table plane at a given fundamental frequency,
with the variation a person shows: the phase wanders (speed varies by a few percent), the
amplitude and the centre drift slowly, the stroke is not a pure sinusoid, the sponge turns a
little with the hand, and the movement ramps up at the start. Every random process is a sum
of sinusoids drawn once from the seed, so the motion is a smooth function of continuous time
(the renderer samples it inside each exposure for motion blur) and its long-run mean
frequency is exactly ``frequency_hz``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PATTERNS = ("circle", "line", "figure8")


@dataclass(frozen=True)
class WipingMotionParams:
    """What the demonstrator does.

    Attributes
    ----------
    pattern : str
        ``circle``, ``line`` (left-right strokes along world y) or ``figure8``.
    frequency_hz : float
        Fundamental frequency of the wiping movement.
    centre_xy : tuple of float
        Centre of the movement on the table, world frame, metres.
    amplitude : float
        Radius (circle) or half stroke (line, figure8 along y), metres.
    amplitude_variation : float
        Relative standard deviation of the slowly varying amplitude.
    speed_variation : float
        Relative standard deviation of the instantaneous frequency.
    centre_drift : float
        Standard deviation of the slow drift of the centre, metres.
    ramp_duration : float
        Time over which the movement grows from rest to full amplitude, seconds.
    yaw_swing : float
        Amplitude of the sponge's turning with each stroke, rad.
    tempo_step : tuple of float or None
        (time s, factor): from that time on the person wipes ``factor`` times as fast (a
        deliberate change of tempo; the phase stays continuous).
    """

    pattern: str = "circle"
    frequency_hz: float = 1.0
    centre_xy: tuple[float, float] = (0.68, 0.0)
    amplitude: float = 0.09
    amplitude_variation: float = 0.07
    speed_variation: float = 0.04
    centre_drift: float = 0.008
    ramp_duration: float = 1.0
    yaw_swing: float = 0.10
    tempo_step: tuple[float, float] | None = None

    def __post_init__(self):
        if self.pattern not in PATTERNS:
            raise ValueError(f"pattern must be one of {', '.join(PATTERNS)}, got {self.pattern!r}")
        if self.frequency_hz <= 0 or self.amplitude <= 0:
            raise ValueError("frequency_hz and amplitude must be positive")
        if self.tempo_step is not None and not self.tempo_step[1] > 0:
            raise ValueError("the tempo step's factor must be positive")


class _SlowProcess:
    """Zero-mean smooth random signal: a sum of sinusoids with random frequencies and phases.

    ``std`` is the standard deviation of the value (``derivative=False``) or, scaled by
    ``1 / (2 pi nu_k)``, of its time derivative (``derivative=True``), over the band
    ``[low_hz, high_hz]``.
    """

    def __init__(self, rng: np.random.Generator, std: float, low_hz: float, high_hz: float,
                 terms: int = 4, derivative: bool = False):
        self.nu = rng.uniform(low_hz, high_hz, terms)
        self.theta = rng.uniform(0.0, 2.0 * np.pi, terms)
        amplitude = np.full(terms, std * np.sqrt(2.0 / terms))
        self.a = amplitude / (2.0 * np.pi * self.nu) if derivative else amplitude

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return np.sin(2.0 * np.pi * np.multiply.outer(t, self.nu) + self.theta) @ self.a


class WipingMotion:
    """The sponge's pose as a function of time.

    Parameters
    ----------
    params : WipingMotionParams
    table_height : float
        World z of the table top, metres.
    sponge_height : float
        Height of the sponge, metres (its centre rides at table height + half of it).
    seed : int
        Seed of every random process.
    """

    def __init__(self, params: WipingMotionParams, table_height: float, sponge_height: float,
                 seed: int):
        self.params = params
        self.centre_z = table_height + 0.5 * sponge_height
        rng = np.random.default_rng([seed, 0x51F0])
        f = params.frequency_hz
        # Phase wander: instantaneous frequency f (1 + e(t)), e with std speed_variation.
        self._phase_wander = _SlowProcess(rng, params.speed_variation * 2 * np.pi * f,
                                          0.04, 0.25, derivative=True)
        self._amplitude_x = _SlowProcess(rng, params.amplitude_variation, 0.02, 0.2)
        self._amplitude_y = _SlowProcess(rng, params.amplitude_variation, 0.02, 0.2)
        self._drift_x = _SlowProcess(rng, params.centre_drift, 0.01, 0.08)
        self._drift_y = _SlowProcess(rng, params.centre_drift, 0.01, 0.08)
        self._yaw_drift = _SlowProcess(rng, 0.08, 0.01, 0.1)
        self._stroke_shape = rng.uniform(0.06, 0.14), rng.uniform(0.0, 2 * np.pi)
        self._yaw0 = 0.5 * np.pi + rng.uniform(-0.25, 0.25)
        self._press = _SlowProcess(rng, 0.0004, 0.3, 1.5)

    def phase(self, t: np.ndarray) -> np.ndarray:
        """Stroke phase (rad), shape like ``t``: ``2 pi f t`` (f times the step's factor
        after a tempo step) plus a bounded wander."""
        t = np.asarray(t, dtype=np.float64)
        elapsed = t
        if self.params.tempo_step is not None:
            at, factor = self.params.tempo_step
            elapsed = t + (factor - 1.0) * np.maximum(t - at, 0.0)
        return 2.0 * np.pi * self.params.frequency_hz * elapsed + self._phase_wander(t)

    def pose(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sponge centre and yaw at times ``t``.

        Parameters
        ----------
        t : ndarray, shape (n,)
            Seconds since the start of the recording.

        Returns
        -------
        centre : ndarray, shape (n, 3)
            Sponge centre in the world frame, metres.
        yaw : ndarray, shape (n,)
            Rotation of the sponge about world z, rad (0: long side along world x).
        """
        p = self.params
        t = np.atleast_1d(np.asarray(t, dtype=np.float64))
        shape, shape_phase = self._stroke_shape
        phi = self.phase(t)
        phi = phi + shape * np.sin(2.0 * phi + shape_phase)  # strokes are not pure sinusoids
        ramp = np.clip(t / p.ramp_duration, 0.0, 1.0) if p.ramp_duration > 0 else np.ones_like(t)
        ramp = ramp * ramp * (3.0 - 2.0 * ramp)
        ax = p.amplitude * ramp * (1.0 + self._amplitude_x(t))
        ay = p.amplitude * ramp * (1.0 + self._amplitude_y(t))
        if p.pattern == "circle":
            dx, dy = ax * np.cos(phi), ay * np.sin(phi)
        elif p.pattern == "line":
            dy = ay * np.sin(phi)
            dx = 0.8 * dy * dy  # the forearm swings about the elbow: strokes bend into an arc
        else:  # figure8
            dy = ay * np.sin(phi)
            dx = 0.5 * ax * np.sin(2.0 * phi)
        x = p.centre_xy[0] + self._drift_x(t) + dx
        y = p.centre_xy[1] + self._drift_y(t) + dy
        z = self.centre_z - self._press(t)  # the hand presses the sponge by a fraction of a mm
        yaw = self._yaw0 + self._yaw_drift(t) + p.yaw_swing * ramp * np.sin(phi + 0.6)
        return np.column_stack([x, y, z]), yaw
