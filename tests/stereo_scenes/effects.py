"""Camera and lighting effects on rendered frames: lighting drift (gain and colour
temperature), a soft shadow drifting across the view, per-camera white balance and sensor
noise. Lens blur and motion blur happen while drawing (:mod:`render`); codec artefacts when
writing (:mod:`video`).
"""

from __future__ import annotations

import cv2
import numpy as np

from tests.stereo_scenes.motion import SmoothWander

NOISE_POOL = 6
NOISE_MARGIN = 16


class FrameEffects:
    """Applies the effects of a plan to frames of one scene (both cameras).

    Parameters
    ----------
    effects : plan.Effects
    duration : float
        Seconds of the demo (the drifts span it).
    size : (int, int)
        (width, height) of the frames.
    rng : numpy Generator
    """

    def __init__(self, effects, duration: float, size: tuple[int, int], rng: np.random.Generator):
        self.spec = effects
        w, h = size
        t = np.linspace(0, duration, 200)
        self._gain = SmoothWander(rng, 0.5 / max(duration, 1), 3 / max(duration, 1), 3)
        self._colour = SmoothWander(rng, 0.5 / max(duration, 1), 3 / max(duration, 1), 3)
        self._gain_peak = max(1e-9, np.abs(self._gain(t)).max())
        self._colour_peak = max(1e-9, np.abs(self._colour(t)).max())
        self.duration = duration
        self.rng = rng
        noise = rng.normal(0, effects.noise_grey, (NOISE_POOL, h + NOISE_MARGIN, w + NOISE_MARGIN, 3))
        noise = np.round(noise)
        self.noise_up = np.clip(noise, 0, 255).astype(np.uint8)
        self.noise_down = np.clip(-noise, 0, 255).astype(np.uint8)
        self.shadow = None
        if effects.moving_shadow:
            yy, xx = np.mgrid[0:2 * h, 0:2 * w].astype(np.float32)
            radius = rng.uniform(0.25, 0.5) * w
            blob = np.exp(-0.5 * (((xx - w) / radius) ** 2 + ((yy - h) / (0.7 * radius)) ** 2))
            darkness = rng.uniform(0.12, 0.3)
            gain = (1.0 - darkness * blob) * 255.0
            self.shadow = cv2.merge([gain.astype(np.uint8)] * 3)
            self.shadow_path = rng.uniform(0, 1, (2, 2)) * [w, h]

    def gains(self, t: float, camera: int) -> tuple[float, float, float]:
        """Per-channel (B, G, R) gains at time t for camera 0 (left) or 1 (right)."""
        g = 1.0 + self.spec.gain_drift * self._gain(t) / self._gain_peak
        c = self.spec.colour_drift * self._colour(t) / self._colour_peak
        balance = self.spec.white_balance_left if camera == 0 else self.spec.white_balance_right
        return tuple(float(v) for v in np.array([1 + c, 1.0, 1 - c]) * g * np.array(balance))

    def apply(self, frame: np.ndarray, t: float, camera: int) -> np.ndarray:
        """The frame as the camera records it at time t (new array)."""
        h, w = frame.shape[:2]
        out = cv2.multiply(frame, (*self.gains(t, camera), 0.0))
        if self.shadow is not None:
            a = t / max(self.duration, 1e-9)
            x, y = (1 - a) * self.shadow_path[0] + a * self.shadow_path[1]
            x, y = int(round(x)), int(round(y))
            out = cv2.multiply(out, self.shadow[y:y + h, x:x + w], scale=1 / 255.0)
        i = int(self.rng.integers(NOISE_POOL))
        dx, dy = (int(v) for v in self.rng.integers(0, NOISE_MARGIN, 2))
        out = cv2.add(out, self.noise_up[i, dy:dy + h, dx:dx + w])
        return cv2.subtract(out, self.noise_down[i, dy:dy + h, dx:dx + w])
