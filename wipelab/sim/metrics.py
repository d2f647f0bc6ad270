"""What a wiping run achieved: force regulation, contact, coverage, learned-height accuracy.

Pure numpy on a session's trace (see :class:`~wipelab.sim.session.Trace`).

- Force: RMS of |F| - F_0 and the peak |F|, with F the contact force as the robot measures it
  (F/T sensor, gravity/inertia compensated, filtered) - the paper's Figs. 6-7, bottom.
- Contact: fraction of control periods in which the surface pushes on the sponge with more
  than ``CONTACT_FORCE`` (the simulator's true contact force; robosuite's 1 N).
- Coverage (robosuite-style): the wiped area is the set of ``COVERAGE_CELL`` cells under the
  sponge's bottom face during the run; a cell counts as wiped when the sponge presses with
  more than ``CONTACT_FORCE`` while its bottom is within ``COVERAGE_GAP`` of the surface
  above that cell (the simulated sponge is a rigid box on a spring; a foam sponge gives
  locally by a few millimetres).
- Profile: the learned height against the true contact height along the path.
"""

from __future__ import annotations

import numpy as np

from wipelab.rotations import rotations_from_quaternions_xyzw
from wipelab.sim.sponge import bottom_points

#: Contact threshold (N).
CONTACT_FORCE = 1.0
#: Side of a coverage cell (m).
COVERAGE_CELL = 0.01
#: Largest gap (m) between sponge bottom and surface for a cell to count as touched.
COVERAGE_GAP = 0.005


def force_metrics(force: np.ndarray, sponge_force: np.ndarray, target_force: float) -> dict:
    """Force regulation over a window.

    Parameters
    ----------
    force : array, shape (n, 3)
        Measured contact force (N, world).
    sponge_force : array, shape (n,)
        True normal force surface -> sponge (N).
    target_force : float
        F_0 (N).
    """
    norm = np.linalg.norm(np.asarray(force, dtype=float), axis=1)
    return {"rms_force_error_n": float(np.sqrt(np.mean((norm - target_force) ** 2))),
            "mean_force_n": float(norm.mean()),
            "peak_force_n": float(norm.max()),
            "contact_fraction": float(np.mean(np.asarray(sponge_force) > CONTACT_FORCE))}


def coverage(height_at, sponge_pos: np.ndarray, sponge_quat: np.ndarray,
             sponge_force: np.ndarray, size) -> dict:
    """Fraction of the wiped area's cells that were wiped (see the module docstring).

    Parameters
    ----------
    height_at : callable
        True surface height (m) at world points (..., 2).
    sponge_pos : array, shape (n, 3)
        Sponge centre (m, world), as simulated (compressed).
    sponge_quat : array, shape (n, 4)
        Sponge orientation (x, y, z, w).
    sponge_force : array, shape (n,)
        True normal force on the sponge (N).
    size : (3,)
        Sponge size (m).
    """
    local = bottom_points(size, (11, 8))
    rotations = rotations_from_quaternions_xyzw(sponge_quat)
    world = np.asarray(sponge_pos)[:, None, :] + np.einsum("nij,kj->nki", rotations, local)
    cells = np.floor(world[..., :2] / COVERAGE_CELL).astype(np.int64)
    keys = cells[..., 0] * (1 << 32) + cells[..., 1]      # one integer per cell
    gap = world[..., 2] - height_at(world[..., :2])
    touched = (gap < COVERAGE_GAP) & (np.asarray(sponge_force)[:, None] > CONTACT_FORCE)
    area, wiped = np.unique(keys).size, np.unique(keys[touched]).size
    return {"coverage": wiped / max(area, 1), "wiped_cells": int(wiped), "area_cells": int(area),
            "cell_m": COVERAGE_CELL}


def profile_error(learned: np.ndarray, expected: np.ndarray) -> dict:
    """Learned height (n,) against the true contact height (n,) along the path (m)."""
    error = np.asarray(learned, dtype=float) - np.asarray(expected, dtype=float)
    return {"rms_height_error_m": float(np.sqrt(np.mean(error ** 2))),
            "max_height_error_m": float(np.max(np.abs(error))),
            "mean_height_error_m": float(error.mean()),
            "true_height_range_m": float(np.ptp(expected)),
            "learned_height_range_m": float(np.ptp(learned))}
