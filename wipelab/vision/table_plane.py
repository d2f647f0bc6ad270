"""The plane the sponge slides on, and sponge positions constrained to it.

A wiping sponge stays on the table: its tracked point moves in a plane. Stereo alone fixes
that point poorly along the line of sight (at 1.5 m with a 6 cm baseline one pixel of
disparity is 8 cm of depth), while each camera fixes it well across the line of sight
(a pixel is a few millimetres). So the tracker

1. fits the plane to the stereo-triangulated points of many frames (:func:`fit_plane`:
   robust total least squares, optionally pulled towards a prior normal, e.g. the world's
   z axis when the calibration gives a world frame), and
2. places each frame's point on that plane where it best explains both cameras' image
   measurements (:func:`points_on_plane`: Gauss-Newton on the reprojection error in
   pixels, two unknowns per frame).

All in one frame (the tracker uses the left camera's optical frame): ``normal . X = offset``
for points X on the plane; ``normal`` is unit length and points towards the cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True)
class Plane:
    """A plane ``normal . X = offset`` (metres).

    Attributes
    ----------
    normal : ndarray, shape (3,)
        Unit normal.
    offset : float
        Signed distance of the plane from the origin along ``normal``.
    residual : float
        Robust scale (1.48 MAD) of the fitted points' distances from the plane, metres
        (0 for a plane that was not fitted).
    count : int
        Points the plane was fitted to.
    """

    normal: np.ndarray
    offset: float
    residual: float = 0.0
    count: int = 0

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distances (...,) of points (..., 3) from the plane."""
        return _dot(np.asarray(points, dtype=np.float64), self.normal) - self.offset

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(origin, e1, e2): the point of the plane nearest the frame's origin and two unit
        vectors spanning the plane (right-handed with the normal); not to be changed."""
        return self._basis

    @cached_property
    def _basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`basis`, worked out once per plane (the tracker asks for it every frame)."""
        helper = np.eye(3)[int(np.argmin(np.abs(self.normal)))]
        e1 = np.cross(helper, self.normal)
        e1 /= np.linalg.norm(e1)
        return self.offset * self.normal, e1, np.cross(self.normal, e1)

    def intersect(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Where rays (origins (..., 3), directions (..., 3)) meet the plane, (..., 3); NaN
        for rays parallel to it."""
        along = np.asarray(directions) @ self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (self.offset - np.asarray(origins) @ self.normal) / along
        s = np.where(np.abs(along) > 1e-12, s, np.nan)
        return origins + s[..., None] * directions

    def shifted(self, distance: float) -> "Plane":
        """The parallel plane ``distance`` metres further along the normal."""
        return Plane(self.normal, self.offset + distance, self.residual, self.count)


def _dot(points: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``points @ vector`` (..., 3) x (3,) without BLAS: the same bits whatever the number
    of BLAS threads (a multi-threaded sum over many points is not reproducible)."""
    return np.einsum("...i,i->...", points, vector)


def table_axes(normal: np.ndarray) -> np.ndarray:
    """Axes (3, 3) of a table frame in the frame ``normal`` (3,) is given in: columns x, y, z
    with z the normal and x the frame's x axis projected onto the table (its y axis when x
    is nearly normal to the table). Yaw angles about the table normal are measured from
    this x."""
    normal = np.asarray(normal, dtype=np.float64)
    x = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    if np.linalg.norm(x) < 0.1:
        x = np.array([0.0, 1.0, 0.0]) - normal[1] * normal
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(normal, x), normal])


def fit_plane(points: np.ndarray, towards: np.ndarray, prior_normal: np.ndarray | None = None,
              prior_sigma: float = np.deg2rad(3.0), iterations: int = 10) -> Plane:
    """Robust total-least-squares plane through points.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Points, n >= 3; NaN rows are ignored.
    towards : ndarray, shape (3,)
        A point on the normal's side of the plane (the cameras): fixes the normal's sign.
    prior_normal : ndarray, shape (3,), optional
        Expected normal (e.g. the world's up axis): the fit minimises
        ``sum(w d^2) / sigma^2 + angle^2 / prior_sigma^2`` (small angles), so that a
        degenerate spread of points (a straight stroke) still gives a plane, and a fit that
        the data determine well is hardly moved.
    prior_sigma : float
        Standard deviation of the normal's angle from ``prior_normal``, rad.
    iterations : int
        Reweighting rounds (Tukey biweight at 4.7 robust sigmas).

    Raises
    ------
    ValueError
        Fewer than three finite points.
    """
    points = np.asarray(points, dtype=np.float64)
    points = points[np.all(np.isfinite(points), axis=1)]
    if len(points) < 3:
        raise ValueError("a plane needs at least three points")
    weights = np.ones(len(points))
    normal, offset, scale = np.array([0.0, 0.0, 1.0]), 0.0, 0.0
    for _ in range(iterations):
        centre = np.einsum("n,ni->i", weights, points) / weights.sum()
        spread = points - centre
        scatter = np.einsum("ni,nj->ij", spread * weights[:, None], spread)
        if prior_normal is not None:
            # residual variance of the current fit, floored: the prior's pull in the units
            # of the scatter matrix (see the docstring)
            variance = max(scale, 1e-4) ** 2
            scatter = scatter + variance / prior_sigma ** 2 * (
                np.eye(3) - np.outer(prior_normal, prior_normal))
        values, vectors = np.linalg.eigh(scatter)
        normal = vectors[:, 0]
        if normal @ (np.asarray(towards) - centre) < 0:
            normal = -normal
        offset = float(normal @ centre)
        distances = _dot(points, normal) - offset
        scale = 1.4826 * float(np.median(np.abs(distances - np.median(distances))))
        if scale <= 1e-9:
            break
        u = distances / (4.685 * scale)
        weights = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        if weights.sum() < 3:
            break
    return Plane(normal, offset, scale, len(points))


def points_on_plane(plane: Plane, rays: list[np.ndarray], cameras: list[tuple[np.ndarray,
                    np.ndarray, np.ndarray]], iterations: int = 3) -> np.ndarray:
    """Per frame, the point of ``plane`` whose projections best match the measured rays.

    Parameters
    ----------
    plane : Plane
    rays : list of ndarray, shape (n, 3)
        Per camera, the measured viewing rays (x, y, 1) in that camera's optical frame
        (undistorted normalised image coordinates); NaN rows where a camera has no
        measurement.
    cameras : list of (R, t, f)
        Per camera, its pose (``x_cam = R x + t`` for points x in the plane's frame) and its
        focal length in pixels (weights the residuals so that they are in pixels).
    iterations : int
        Gauss-Newton steps from the mean of the rays' intersections with the plane.

    Returns
    -------
    ndarray, shape (n, 3)
        Points in the plane's frame; NaN where no camera measured.

    Each frame's point starts where the mean of its rays meets the plane; each Gauss-Newton
    step solves the 2 x 2 normal equations of the pixel residuals in the plane's coordinates
    (a, b). The tracker asks for one point per frame: a few hundred operations on Python
    floats (~0.05 ms), where a compiled kernel would spend ~0.6 s of every process loading.
    """
    origin, e1, e2 = (v.tolist() for v in plane.basis())
    normal, offset = np.asarray(plane.normal, np.float64).tolist(), float(plane.offset)
    views = []
    for R, t, focal in cameras:
        R, t = np.asarray(R, np.float64).tolist(), np.asarray(t, np.float64).tolist()
        eye = [-v for v in _rotate_back(R, t)]
        views.append((R, t, float(focal), eye, _rotate(R, e1), _rotate(R, e2)))
    per_camera = [np.asarray(r, np.float64).tolist() for r in rays]
    points = np.full((len(per_camera[0]), 3), np.nan)
    for i, measured in enumerate(zip(*per_camera)):
        seen = [(view, ray) for view, ray in zip(views, measured) if math.isfinite(ray[0])]
        start, count = [0.0, 0.0, 0.0], 0
        for (R, _, _, eye, _, _), ray in seen:
            direction = _rotate_back(R, ray)
            along = _dot3(direction, normal)
            if abs(along) <= 1e-12:
                continue
            reach = (offset - _dot3(eye, normal)) / along
            start = [s + (o + reach * d) for s, o, d in zip(start, eye, direction)]
            count += 1
        if count == 0:
            continue
        relative = [s / count - o for s, o in zip(start, origin)]
        a, b = _dot3(relative, e1), _dot3(relative, e2)
        for _ in range(iterations):
            X = [o + a * u + b * v for o, u, v in zip(origin, e1, e2)]
            aa = ab = bb = ga = gb = 0.0
            for (R, t, focal, _, d1, d2), ray in seen:
                camera = [c + s for c, s in zip(_rotate(R, X), t)]
                z = camera[2]
                x, y = camera[0] / z, camera[1] / z
                residual_x, residual_y = focal * (x - ray[0]), focal * (y - ray[1])
                weight = focal / z
                # d(projection)/d(a), d(projection)/d(b), in pixels
                ja_x, ja_y = weight * (d1[0] - x * d1[2]), weight * (d1[1] - y * d1[2])
                jb_x, jb_y = weight * (d2[0] - x * d2[2]), weight * (d2[1] - y * d2[2])
                aa += ja_x * ja_x + ja_y * ja_y
                ab += ja_x * jb_x + ja_y * jb_y
                bb += jb_x * jb_x + jb_y * jb_y
                ga += ja_x * residual_x + ja_y * residual_y
                gb += jb_x * residual_x + jb_y * residual_y
            determinant = aa * bb - ab * ab
            if abs(determinant) > 1e-12:
                a -= (bb * ga - ab * gb) / determinant
                b -= (aa * gb - ab * ga) / determinant
        points[i] = [o + a * u + b * v for o, u, v in zip(origin, e1, e2)]
    return points


def _dot3(u, v) -> float:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _rotate(R, v) -> list[float]:
    """``R @ v`` for a 3 x 3 matrix (nested lists)."""
    return [R[0][0] * v[0] + R[0][1] * v[1] + R[0][2] * v[2],
            R[1][0] * v[0] + R[1][1] * v[1] + R[1][2] * v[2],
            R[2][0] * v[0] + R[2][1] * v[1] + R[2][2] * v[2]]


def _rotate_back(R, v) -> list[float]:
    """``R.T @ v`` for a 3 x 3 matrix (nested lists)."""
    return [R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
            R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
            R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2]]
