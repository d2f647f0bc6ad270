"""Particle-filter building blocks: weights from log-likelihoods, resampling, estimates.

A particle set is an array of states, shape (n, d), with weights (n,) that sum to one. The
sponge tracker's state is (x, y, z, yaw); yaw is an angle of a box, so it is averaged on
the doubled angle (a box turned by pi looks the same).
"""

from __future__ import annotations

import numpy as np


def normalised_weights(log_likelihood: np.ndarray) -> np.ndarray:
    """Weights proportional to ``exp(log_likelihood)``, summing to one, shape (n,)."""
    shifted = np.exp(log_likelihood - np.max(log_likelihood))
    return shifted / shifted.sum()


def effective_sample_size(weights: np.ndarray) -> float:
    """``1 / sum(w^2)``: n for uniform weights, 1 when one particle holds all the weight."""
    return float(1.0 / np.sum(weights * weights))


def systematic_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices of the particles to keep (n,), drawn by systematic resampling.

    One uniform draw places n evenly spaced pointers on the cumulative weights: low variance
    and O(n).
    """
    n = len(weights)
    pointers = (rng.random() + np.arange(n)) / n
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0
    return np.searchsorted(cumulative, pointers, side="left")


def weighted_pose_mean(poses: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted mean of (x, y, z, yaw) poses, yaw modulo pi (box symmetry), shape (4,)."""
    position = weights @ poses[:, :3]
    doubled = weights @ np.exp(2j * poses[:, 3])
    return np.append(position, 0.5 * np.angle(doubled))


def wrap_half_turn(yaw: np.ndarray) -> np.ndarray:
    """Angles mapped into [-pi/2, pi/2) (a box's yaw is defined modulo pi)."""
    return (np.asarray(yaw) + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def align_yaw(poses: np.ndarray, reference_yaw: float) -> np.ndarray:
    """Copy of poses (n, >=4) with each yaw replaced by its box-equivalent (modulo pi)
    nearest to ``reference_yaw``, so that faces named in the sponge frame match."""
    aligned = np.array(poses, dtype=np.float64, copy=True)
    aligned[:, 3] = reference_yaw + wrap_half_turn(aligned[:, 3] - reference_yaw)
    return aligned
