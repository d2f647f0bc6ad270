"""Sub-millimetre pose refinement: damped Newton ascent on a smooth score.

The particle filter finds the sponge; this step polishes its estimate. The score (summed
silhouette contrast of both cameras, :mod:`wipelab.vision.sponge_likelihood`) is smooth in
the pose because it reads blurred images with bilinear interpolation; its gradient and
Hessian come from image derivatives chained with the projection's Jacobian, so one Newton
step costs a handful of image look-ups.

These numpy functions are the reference; the tracker runs the same loop compiled
(:mod:`wipelab.vision._refinement_kernel`, through
:meth:`wipelab.vision.sponge_likelihood.SilhouetteContrast.refine`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def newton_step(gradient: np.ndarray, hessian: np.ndarray, scale: np.ndarray,
                max_step: float) -> np.ndarray:
    """Ascent step for a local quadratic model.

    The Newton step where it climbs (the model curves down along it); elsewhere a gradient
    step scaled by the magnitude of the curvature along each axis. Each component is
    clipped to ``max_step * scale``.

    Parameters
    ----------
    gradient : ndarray, shape (d,)
    hessian : ndarray, shape (d, d)
    scale : ndarray, shape (d,)
        Typical length of each coordinate (metres, radians).
    max_step : float
        Largest step per axis, in units of ``scale``.
    """
    try:
        step = -np.linalg.solve(hessian, gradient)
    except np.linalg.LinAlgError:
        step = None
    if step is None or gradient @ step <= 0 or step @ hessian @ step >= 0:
        curvature = np.maximum(np.abs(np.diag(hessian)), np.abs(gradient) / (max_step * scale))
        step = gradient / np.maximum(curvature, 1e-12)
    return np.clip(step, -max_step * scale, max_step * scale)


def refine_pose(derivatives: Callable[[np.ndarray], tuple[float, np.ndarray, np.ndarray]],
                score: Callable[[np.ndarray], np.ndarray], start: np.ndarray,
                scale: np.ndarray, iterations: int = 6, max_step: float = 4.0,
                tolerance: float = 0.1) -> tuple[np.ndarray, float]:
    """Maximise a score near ``start`` by damped Newton steps.

    Parameters
    ----------
    derivatives : callable
        ``derivatives(pose)`` -> (value, gradient (d,), Hessian (d, d)) at ``pose``.
    score : callable
        Maps poses (n, d) to values (n,); used to accept or shorten a step.
    start : ndarray, shape (d,)
    scale : ndarray, shape (d,)
        Typical length of each coordinate; ``max_step`` and ``tolerance`` are in its units.
    iterations : int
        Most Newton steps.
    max_step : float
        Largest step per axis.
    tolerance : float
        Stop when every component of the next step is below this.

    Returns
    -------
    pose : ndarray, shape (d,)
    value : float
        Score at ``pose``.
    """
    scale = np.asarray(scale, dtype=np.float64)
    pose = np.asarray(start, dtype=np.float64).copy()
    value = -np.inf
    for _ in range(iterations):
        value, gradient, hessian = derivatives(pose)
        step = newton_step(gradient, hessian, scale, max_step)
        if np.all(np.abs(step) < tolerance * scale):  # converged: no need to try the step
            break
        # fall back on plain gradient steps where the quadratic model is poor
        climb = gradient * scale ** 2
        climb /= max(np.max(np.abs(climb / scale)), 1e-300)
        steps = np.vstack([np.outer([1.0, 0.5, 0.25], step), np.outer([2.0, 1.0, 0.5], climb)])
        values = score(pose + steps)
        best = int(np.argmax(values))
        if values[best] <= value:  # no progress in any direction: converged
            break
        pose, value = pose + steps[best], float(values[best])
        if np.all(np.abs(steps[best]) < tolerance * scale):
            break
    return pose, float(value)
