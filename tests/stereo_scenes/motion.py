"""Human-like wiping motion of the sponge on the table (this generator's own model).

The sponge's centre follows a periodic pattern in the table plane (circle, ellipse, line,
figure-8) whose phase advances at a nominal frequency with a slow tempo wander (zero mean
over the demo, so the mean rate of the moving part is the nominal frequency), with drifting
amplitude and centre, an uneven speed along the stroke, a yaw that follows the stroke a little
and a small tilt in the direction of motion; the bottom of the sponge stays on the table.
A still phase at the start is followed by a smooth start-up over ``RAMP_S``.
"""

from __future__ import annotations

import numpy as np

from tests.stereo_scenes.camera import rotation

RAMP_S = 0.6          # seconds from standing still to the full tempo
GRID_S = 1e-3         # time step of the integrated phase
PATTERNS = ("circle", "ellipse", "line", "figure8")


class SmoothWander:
    """A smooth random signal of about unit RMS: a sum of sinusoids, (f_low, f_high) Hz."""

    def __init__(self, rng: np.random.Generator, f_low: float, f_high: float, terms: int = 4):
        self.freq = rng.uniform(f_low, f_high, terms)
        self.phase = rng.uniform(0.0, 2 * np.pi, terms)
        amp = rng.uniform(0.5, 1.0, terms)
        self.amp = amp / np.sqrt(0.5 * np.sum(amp ** 2))

    def __call__(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, float)[..., None]
        return np.sum(self.amp * np.sin(2 * np.pi * self.freq * t + self.phase), axis=-1)


def pattern_offset(pattern: str, phase: np.ndarray, half_across: np.ndarray, aspect: float,
                   bend: float) -> np.ndarray:
    """In-plane offsets (n, 2) along the pattern's (major, minor) axes, metres."""
    a, b = half_across, half_across * aspect
    if pattern in ("circle", "ellipse"):
        return np.stack([a * np.cos(phase), b * np.sin(phase)], axis=-1)
    if pattern == "line":
        return np.stack([a * np.sin(phase), bend * a * np.sin(2 * phase)], axis=-1)
    if pattern == "figure8":
        return np.stack([a * np.sin(phase), b * np.sin(2 * phase)], axis=-1)
    raise ValueError(f"unknown pattern {pattern!r}; expected one of {PATTERNS}")


class WipingMotion:
    """Pose of the sponge over time.

    Parameters
    ----------
    pattern : str
        One of :data:`PATTERNS`.
    frequency_hz : float
        Nominal stroke frequency (mean rate of the moving part).
    across : float
        Size of the pattern along its major axis, metres.
    aspect : float
        Minor / major size (ellipse, figure-8; 1 for a circle).
    centre_xy : (2,) array
        Pattern centre on the table, world metres.
    orientation : float
        Direction of the major axis in the table plane (rad from world x).
    table_z : float
        Height of the table top, metres.
    half_extents : (3,) array
        Half length, width and height of the whole sponge (body + pad), metres.
    yaw0 : float
        Mean yaw of the sponge's long axis (rad from world x).
    still_s : float
        Seconds without motion at the start.
    duration : float
        Seconds covered.
    rng : numpy Generator
        Draws the wanders.
    """

    def __init__(self, pattern, frequency_hz, across, aspect, centre_xy, orientation, table_z,
                 half_extents, yaw0, still_s, duration, rng):
        self.pattern, self.frequency_hz = pattern, float(frequency_hz)
        self.across, self.aspect = float(across), float(aspect)
        self.centre_xy = np.asarray(centre_xy, float)
        self.orientation, self.table_z = float(orientation), float(table_z)
        self.half_extents = np.asarray(half_extents, float)
        self.yaw0, self.still_s = float(yaw0), float(still_s)
        self.tempo_wander = rng.uniform(0.02, 0.035)      # RMS; peaks near +-5 %
        self.amplitude_wander = rng.uniform(0.03, 0.07)
        self.centre_wander = rng.uniform(0.005, 0.015)    # metres RMS
        self.speed_unevenness = rng.uniform(0.0, 0.12)
        self.speed_phase = rng.uniform(0, 2 * np.pi)
        self.bend = rng.uniform(-0.06, 0.06)
        self.yaw_follow = rng.uniform(0.03, 0.15)
        self.yaw_phase = rng.uniform(0, 2 * np.pi)
        self.max_tilt = np.radians(rng.uniform(0.5, 3.0))
        self._tempo = SmoothWander(rng, 0.02, 0.15)
        self._amplitude = SmoothWander(rng, 0.02, 0.1)
        self._centre = (SmoothWander(rng, 0.01, 0.08), SmoothWander(rng, 0.01, 0.08))
        self._yaw = SmoothWander(rng, 0.02, 0.1)
        self._grid = np.arange(-1.0, duration + 1.0, GRID_S)
        self._phase = self._integrate_phase(duration)

    def _integrate_phase(self, duration: float) -> np.ndarray:
        t = self._grid
        ramp = np.clip((t - self.still_s) / RAMP_S, 0.0, 1.0)
        ramp = ramp * ramp * (3 - 2 * ramp)
        wander = self._tempo(t)
        moving = (t >= self.still_s + RAMP_S) & (t <= duration)
        if np.any(moving):
            wander = wander - wander[moving].mean()
        rate = 2 * np.pi * self.frequency_hz * (1.0 + self.tempo_wander * wander) * ramp
        return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * GRID_S)])

    def phase(self, t: np.ndarray) -> np.ndarray:
        """Stroke phase (rad) at times t (s)."""
        return np.interp(t, self._grid, self._phase)

    def centre_xy_at(self, t: np.ndarray) -> np.ndarray:
        """Sponge centre in the table plane, (n, 2) world metres."""
        t = np.atleast_1d(np.asarray(t, float))
        phase = self.phase(t)
        phase = phase + self.speed_unevenness * np.sin(2 * phase + self.speed_phase)
        half = 0.5 * self.across * (1.0 + self.amplitude_wander * self._amplitude(t))
        local = pattern_offset(self.pattern, phase, half, self.aspect, self.bend)
        c, s = np.cos(self.orientation), np.sin(self.orientation)
        world = local @ np.array([[c, s], [-s, c]])
        drift = self.centre_wander * np.stack([w(t) for w in self._centre], axis=-1)
        return self.centre_xy + world + drift

    def pose(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre (n, 3), orientation (n, 3, 3) (sponge frame -> world) and yaw (n,) at t.

        The sponge frame has x along its length, y across, z up out of its top face.
        """
        t = np.atleast_1d(np.asarray(t, float))
        xy = self.centre_xy_at(t)
        dt = 0.01
        velocity = (self.centre_xy_at(t + dt) - self.centre_xy_at(t - dt)) / (2 * dt)
        speed = np.linalg.norm(velocity, axis=1)
        yaw = (self.yaw0 + self.yaw_follow * np.sin(self.phase(t) + self.yaw_phase)
               + 0.05 * self._yaw(t))
        peak_speed = np.pi * self.across * self.frequency_hz * 1.2
        tilt = self.max_tilt * np.clip(speed / peak_speed, 0.0, 1.0)
        R = np.empty((t.size, 3, 3))
        centre = np.empty((t.size, 3))
        for i in range(t.size):
            R_yaw = rotation([0, 0, 1], yaw[i])
            if speed[i] > 1e-6:
                axis = np.array([-velocity[i, 1], velocity[i, 0], 0.0]) / speed[i]
                R[i] = rotation(axis, -tilt[i]) @ R_yaw  # leading edge up
            else:
                R[i] = R_yaw
            lift = np.sum(np.abs(R[i][2, :]) * self.half_extents)
            centre[i] = [xy[i, 0], xy[i, 1], self.table_z + lift]
        return centre, R, yaw
