"""The 6D force/torque sensor at the right wrist: noise, bias, gravity compensation, low-pass.

Reading convention: the wrench (force N, torque N m about the sensor origin) that the wrist
exerts on everything beyond the sensor (hand + sponge, the *payload*), in the sensor frame
(``hand_r``: at the wrist centre, parallel to the forearm link frame), plus an unknown
constant bias and white noise.

Gravity compensation as on a real robot: the payload's mass, centre of mass and the bias are
identified by least squares from static readings in a few hand orientations
(:func:`identify_payload`); then :func:`contact_wrench` removes the payload's weight and
inertia (m a, from the commanded TCP acceleration) and returns the wrench the environment
exerts on the tool, in the world frame. Rotational inertia of the payload is neglected.
Pure numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Standard gravity (m/s^2) along world -z.
GRAVITY = np.array([0.0, 0.0, -9.81])


@dataclass(frozen=True)
class FTSensorParams:
    """Sensor imperfections and the controller's filtering."""

    force_noise: float = 0.15       # N: standard deviation of white noise per axis
    torque_noise: float = 0.008     # N m: standard deviation per axis
    force_bias: float = 0.8         # N: magnitude scale of the unknown constant force bias
    torque_bias: float = 0.03       # N m: same for the torque bias
    lowpass_hz: float | None = 25.0  # cut-off of the first-order low-pass (None: off)


@dataclass(frozen=True)
class PayloadModel:
    """What identification found: mass (kg), centre of mass (3,) in the sensor frame (m),
    force bias (3,) (N) and torque bias (3,) (N m), sensor frame; RMS force residual of the
    fit (N): large when a calibration pose was not in free air."""

    mass: float
    com: np.ndarray
    force_bias: np.ndarray
    torque_bias: np.ndarray
    residual: float = 0.0


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def identify_payload(readings: np.ndarray, rotations: np.ndarray,
                     gravity: np.ndarray = GRAVITY) -> PayloadModel:
    """Least-squares payload from static readings in k >= 3 distinct orientations.

    Static model (sensor frame s, g_s = R^T g): f = -m g_s + b_f, tau = m g_s x c + b_t.

    Parameters
    ----------
    readings : array, shape (k, 6)
        Static wrench readings (force, torque) in the sensor frame.
    rotations : array, shape (k, 3, 3)
        Sensor orientation in the world for each reading.
    """
    readings = np.asarray(readings, dtype=float)
    g_s = np.einsum("kji,j->ki", np.asarray(rotations, dtype=float), gravity)   # R^T g
    k = len(readings)
    # force: unknowns (m, b_f)
    a_f = np.zeros((3 * k, 4))
    a_f[:, 0] = -g_s.ravel()
    a_f[:, 1:] = np.tile(np.eye(3), (k, 1))
    solution = np.linalg.lstsq(a_f, readings[:, :3].ravel(), rcond=None)[0]
    mass, force_bias = float(solution[0]), solution[1:]
    residual = float(np.sqrt(np.mean((a_f @ solution - readings[:, :3].ravel()) ** 2)))
    # torque: unknowns (c, b_t) with tau = skew(m g_s) c + b_t
    a_t = np.zeros((3 * k, 6))
    for i in range(k):
        a_t[3 * i:3 * i + 3, :3] = _skew(mass * g_s[i])
        a_t[3 * i:3 * i + 3, 3:] = np.eye(3)
    solution = np.linalg.lstsq(a_t, readings[:, 3:].ravel(), rcond=None)[0]
    return PayloadModel(mass, solution[:3], force_bias, solution[3:], residual)


def contact_wrench(reading: np.ndarray, rotation: np.ndarray, payload: PayloadModel,
                   acceleration=np.zeros(3), gravity: np.ndarray = GRAVITY
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Wrench the environment exerts on the tool, in the world frame.

    Newton for the payload: m a = F_c + m g + F_sensor, so F_c = m (a - g) - F_sensor.

    Parameters
    ----------
    reading : array, shape (6,)
        Sensor reading (force N, torque N m), sensor frame.
    rotation : array, shape (3, 3)
        Sensor orientation in the world.
    payload : PayloadModel
    acceleration : array, shape (3,)
        Payload acceleration (m/s^2, world), e.g. the commanded TCP acceleration.

    Returns
    -------
    force : ndarray, shape (3,) (N, world);  torque : ndarray, shape (3,) (N m about the
    sensor origin, world axes).
    """
    rotation = np.asarray(rotation, dtype=float)
    force = contact_force(reading, rotation, payload, acceleration, gravity)
    (cx, cy, cz), (wx, wy, wz) = rotation @ payload.com, payload.mass * gravity  # lever x weight
    lever_torque = np.array([cy * wz - cz * wy, cz * wx - cx * wz, cx * wy - cy * wx])
    torque = -rotation @ (reading[3:] - payload.torque_bias) - lever_torque
    return force, torque


def contact_force(reading: np.ndarray, rotation: np.ndarray, payload: PayloadModel,
                  acceleration=np.zeros(3), gravity: np.ndarray = GRAVITY) -> np.ndarray:
    """The force part of :func:`contact_wrench` alone (N, world), F_c = m (a - g) - R f_s:
    what the control loop needs every period."""
    return payload.mass * (np.asarray(acceleration, dtype=float) - gravity) \
        - rotation @ (reading[:3] - payload.force_bias)


class FirstOrderLowPass:
    """y_k = y_{k-1} + a (x_k - y_{k-1}), a = dt / (dt + 1 / (2 pi f_c)); pass-through if
    ``cutoff_hz`` is None. Starts at the first sample."""

    def __init__(self, cutoff_hz: float | None, dt: float):
        self.alpha = 1.0 if cutoff_hz is None else dt / (dt + 1.0 / (2.0 * math.pi * cutoff_hz))
        self.state: np.ndarray | None = None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        self.state = x.copy() if self.state is None else self.state + self.alpha * (x - self.state)
        return self.state   # a new array every call: the caller may keep it


class SensorImperfections:
    """Adds a constant bias (drawn once) and white noise to true readings (seeded)."""

    def __init__(self, params: FTSensorParams, rng: np.random.Generator):
        self.params = params
        self.rng = rng
        direction = rng.normal(size=(2, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        self.bias = np.concatenate([params.force_bias * direction[0],
                                    params.torque_bias * direction[1]])
        self._sigma = np.repeat([params.force_noise, params.torque_noise], 3)

    def __call__(self, wrench: np.ndarray) -> np.ndarray:
        return np.asarray(wrench, dtype=float) + self.bias + self._sigma * self.rng.normal(size=6)
