"""3-D geometry of the scene's solids: faces of bevelled boxes, circles, polygon clipping.

Faces are ``(polygon (k, 3), outward normal (3,))`` pairs; solids built from them are convex,
so back-face culling alone orders their faces.
"""

from __future__ import annotations

import itertools

import numpy as np


def _unit(v):
    return np.asarray(v, float) / np.linalg.norm(v)


def bevelled_box_faces(half: np.ndarray, bevel: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Faces of a box with half-extents ``half`` (3,) whose edges are cut by ``bevel`` metres,
    centred at the origin: 6 main faces, 12 edge strips, 8 corner triangles."""
    a = np.asarray(half, float)
    e = min(bevel, 0.45 * a.min())
    faces = []

    def corner_point(signs, axis_full):
        p = np.array([s * (a[i] - (0 if i == axis_full else e)) for i, s in enumerate(signs)])
        return p

    for axis in range(3):
        for s in (-1.0, 1.0):
            u, v = [i for i in range(3) if i != axis]
            poly = []
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                signs = [0.0] * 3
                signs[axis], signs[u], signs[v] = s, su, sv
                poly.append(corner_point(signs, axis))
            normal = np.zeros(3)
            normal[axis] = s
            faces.append((np.array(poly), normal))
    if e <= 0:
        return [_outward(poly, n) for poly, n in faces]
    for i, j in ((0, 1), (0, 2), (1, 2)):
        k = 3 - i - j
        for si, sj in itertools.product((-1.0, 1.0), repeat=2):
            poly = []
            for sk, full in ((-1.0, i), (-1.0, j), (1.0, j), (1.0, i)):
                signs = [0.0] * 3
                signs[i], signs[j], signs[k] = si, sj, sk
                poly.append(corner_point(signs, full))
            normal = np.zeros(3)
            normal[i], normal[j] = si, sj
            faces.append((np.array(poly), _unit(normal)))
    for signs in itertools.product((-1.0, 1.0), repeat=3):
        poly = np.array([corner_point(signs, axis) for axis in range(3)])
        faces.append((poly, _unit(signs)))
    return [_outward(poly, n) for poly, n in faces]


def _outward(poly: np.ndarray, normal: np.ndarray):
    """Orders a convex face's vertices counter-clockwise about its normal."""
    centre = poly.mean(axis=0)
    ref = poly[0] - centre
    ref /= np.linalg.norm(ref)
    other = np.cross(normal, ref)
    angle = np.arctan2((poly - centre) @ other, (poly - centre) @ ref)
    return poly[np.argsort(angle)], normal


def split_faces_at_height(faces, z: float):
    """Cuts faces (local frame) by the plane ``z``: (faces below, faces above)."""
    below, above = [], []
    for poly, normal in faces:
        low = clip_polygon(poly, np.array([0, 0, -1.0]), -z)
        high = clip_polygon(poly, np.array([0, 0, 1.0]), z)
        if len(low) >= 3:
            below.append((low, normal))
        if len(high) >= 3:
            above.append((high, normal))
    return below, above


def clip_polygon(poly: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """The part of a convex polygon (k, 3) where ``points @ normal >= offset``
    (Sutherland-Hodgman)."""
    out = []
    k = len(poly)
    for idx in range(k):
        p, q = poly[idx], poly[(idx + 1) % k]
        dp, dq = p @ normal - offset, q @ normal - offset
        if dp >= 0:
            out.append(p)
        if (dp >= 0) != (dq >= 0):
            out.append(p + (q - p) * (dp / (dp - dq)))
    return np.array(out) if out else np.zeros((0, 3))


def circle(centre, axis_u, axis_v, radius: float, n: int = 24) -> np.ndarray:
    """Points (n, 3) of a circle spanned by two orthonormal axes."""
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)[:, None]
    return (np.asarray(centre, float) + radius * np.cos(angle) * np.asarray(axis_u, float)
            + radius * np.sin(angle) * np.asarray(axis_v, float))


def horizontal_circle(centre, radius: float, n: int = 24) -> np.ndarray:
    """Points (n, 3) of a circle in a horizontal plane."""
    return circle(centre, [1.0, 0, 0], [0, 1.0, 0], radius, n)


def perpendicular_axes(direction) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to ``direction`` and to each other."""
    d = _unit(direction)
    helper = np.array([0, 0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0, 0])
    u = _unit(np.cross(d, helper))
    return u, np.cross(d, u)


def box_corners(half: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of a box centred at the origin."""
    return np.array(list(itertools.product(*[(-h, h) for h in half])))
