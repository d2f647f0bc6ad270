"""Sub-millimetre pose refinement: damped Newton ascent on the summed silhouette contrast.

The particle filter finds the sponge; this step polishes its estimate. The score is the
silhouette contrast of both cameras summed (:mod:`wipelab.vision.sponge_likelihood`, driven
through :meth:`~wipelab.vision.sponge_likelihood.SilhouetteContrast.refine`). It is smooth
in the pose (x, y, z, yaw) because it reads blurred images bilinearly; its gradient and
Hessian come from image derivatives chained with the projection's Jacobian
(:func:`wipelab.vision._likelihood_kernel.contrast_derivatives`), so one Newton step costs
a handful of image look-ups.

Each iteration of :func:`refine_contrast`:

1. evaluates the local quadratic model (value, gradient g, Hessian H) at the current pose;
2. :func:`newton_step` takes the Newton step -H^-1 g where it climbs (g . step > 0) and the
   model curves down along it (step . H step < 0). Where the model is poor - H singular,
   or the Newton step descends or meets no downward curvature - it takes a gradient step
   instead: g_q divided by the magnitude of the curvature along axis q, taken as at least
   |g_q| / (max_step scale_q). Each component is then clipped to +-``max_step * scale_q``;
3. tries the step at 1, 1/2 and 1/4 of its length and the gradient direction (scaled by
   ``scale`` squared, its largest component one ``scale``) at 2, 1 and 1/2, and moves to
   the best of the six if it beats the current score: a poor quadratic model then costs
   a shorter step, not a wrong one.

It stops after ``iterations`` steps, when the next Newton step (or the step just taken) is
smaller than ``tolerance * scale`` in every component, or when none of the six candidates
improves the score.

The 4 x 4 linear solve is Gaussian elimination with partial pivoting (:func:`solve`); a
zero pivot marks the Hessian singular, and the gradient step is taken.

A camera is passed as the tuple ``(MA, MB, MC, weights, is_face, R, t, K, origin, image)``
of :func:`wipelab.vision._likelihood_kernel.score_poses`' arguments; ``views`` is a tuple
of them. :func:`summed_contrast` and :func:`summed_derivatives` sum the cameras' scores
and derivatives; :class:`~wipelab.vision.sponge_likelihood.SilhouetteContrast` calls them
too.

Everything is compiled with numba, so a refinement costs its image reads. Numba's on-disk
cache (``cache=True``) is refreshed when this file or any wipelab module it uses changes
(:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels
from wipelab.vision._likelihood_kernel import contrast_derivatives, score_poses

#: Step multiples tried along the Newton step, then along the scaled gradient.
_NEWTON_FRACTIONS = (1.0, 0.5, 0.25)
_CLIMB_FRACTIONS = (2.0, 1.0, 0.5)


@njit(cache=True)
def solve(A, b):
    """x with ``A x = b`` (d x d) by Gaussian elimination with partial pivoting, and whether
    ``A`` was regular (no zero pivot; where it was not, x is undefined)."""
    d = b.shape[0]
    M = A.copy()
    x = b.copy()
    for col in range(d):
        pivot = col
        for row in range(col + 1, d):
            if abs(M[row, col]) > abs(M[pivot, col]):
                pivot = row
        if M[pivot, col] == 0.0:
            return x, False
        if pivot != col:
            for k in range(d):
                M[col, k], M[pivot, k] = M[pivot, k], M[col, k]
            x[col], x[pivot] = x[pivot], x[col]
        for row in range(col + 1, d):
            factor = M[row, col] / M[col, col]
            for k in range(col, d):
                M[row, k] -= factor * M[col, k]
            x[row] -= factor * x[col]
    for row in range(d - 1, -1, -1):
        total = x[row]
        for k in range(row + 1, d):
            total -= M[row, k] * x[k]
        x[row] = total / M[row, row]
    return x, True


@njit(cache=True)
def newton_step(gradient, hessian, scale, max_step):
    """Ascent step (d,) for the local quadratic model ``gradient``, ``hessian``.

    The Newton step where it climbs and the model curves down along it; elsewhere a
    gradient step scaled by the magnitude of the curvature along each axis. Each component
    is clipped to ``max_step * scale``; ``scale`` (d,) is the typical length of each
    coordinate (metres, radians), ``max_step`` is in its units.
    """
    step, regular = solve(hessian, -gradient)
    if not regular or gradient @ step <= 0.0 or step @ (hessian @ step) >= 0.0:
        for q in range(gradient.shape[0]):
            curvature = max(abs(hessian[q, q]), abs(gradient[q]) / (max_step * scale[q]))
            step[q] = gradient[q] / max(curvature, 1e-12)
    for q in range(gradient.shape[0]):
        limit = max_step * scale[q]
        step[q] = min(max(step[q], -limit), limit)
    return step


@njit(cache=True)
def summed_derivatives(views, pose):
    """Summed contrast of all cameras at ``pose`` (4,) with its gradient (4,) and Hessian
    (4, 4)."""
    value, gradient, hessian = 0.0, np.zeros(4), np.zeros((4, 4))
    for view in views:
        v, g, h = contrast_derivatives(pose, view[0], view[1], view[2], view[3], view[5],
                                       view[6], view[7], view[8], view[9])
        value += v
        gradient += g
        hessian += h
    return value, gradient, hessian


@njit(cache=True)
def summed_contrast(views, poses):
    """Summed contrast of all cameras for poses (n, 4), shape (n,)."""
    total = np.zeros(poses.shape[0])
    for view in views:
        total += score_poses(poses, view[0], view[1], view[2], view[3], view[4], view[5],
                             view[6], view[7], view[8], view[9], False)[0]
    return total


@njit(cache=True)
def _small(step, scale, tolerance):
    for q in range(step.shape[0]):
        if not abs(step[q]) < tolerance * scale[q]:
            return False
    return True


@njit(cache=True)
def refine_contrast(views, start, scale, iterations, max_step, tolerance):
    """Maximise the summed silhouette contrast of ``views`` near ``start`` (4,) by damped
    Newton steps: the refined pose (4,) and its contrast.

    ``scale`` (4,) is the typical length of each coordinate; ``max_step`` (largest step per
    axis) and ``tolerance`` (stop when every component of the next step is below it) are in
    its units; at most ``iterations`` Newton steps.
    """
    pose = start.copy()
    value = -np.inf
    steps = np.empty((6, 4))
    for _ in range(iterations):
        value, gradient, hessian = summed_derivatives(views, pose)
        step = newton_step(gradient, hessian, scale, max_step)
        if _small(step, scale, tolerance):  # converged: no need to try the step
            break
        # fall back on plain gradient steps where the quadratic model is poor
        climb = gradient * scale ** 2
        largest = 0.0
        for q in range(4):
            largest = max(largest, abs(climb[q] / scale[q]))
        climb /= max(largest, 1e-300)
        for m in range(3):
            steps[m] = _NEWTON_FRACTIONS[m] * step
            steps[3 + m] = _CLIMB_FRACTIONS[m] * climb
        values = summed_contrast(views, pose + steps)
        best = int(np.argmax(values))
        if values[best] <= value:  # no progress in any direction: converged
            break
        pose = pose + steps[best]
        value = values[best]
        if _small(steps[best], scale, tolerance):
            break
    return pose, value


forget_stale_kernels(__name__)
