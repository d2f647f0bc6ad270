"""The sponge as a box: its corners, faces and edges in its own frame.

Sponge frame: origin at the box centre (the point tracked and reported as "the sponge
centre"), x along the long side, y along the short side, z up, so that a sponge lying flat
on a table with yaw psi has ``R_world_sponge = Rz(psi)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Corner signs, shape (8, 3): corner i = signs[i] * half extents.
CORNER_SIGNS = np.array([[sx, sy, sz] for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)],
                        dtype=np.float64)
#: Faces as corner indices, counter-clockwise seen from outside, and their outward normals.
FACES = np.array([[0, 2, 3, 1],   # bottom (-z)
                  [4, 5, 7, 6],   # top (+z)
                  [0, 1, 5, 4],   # -y
                  [2, 6, 7, 3],   # +y
                  [0, 4, 6, 2],   # -x
                  [1, 3, 7, 5]])  # +x
FACE_NORMALS = np.array([[0, 0, -1], [0, 0, 1], [0, -1, 0], [0, 1, 0], [-1, 0, 0], [1, 0, 0]],
                        dtype=np.float64)
#: The 12 edges as corner-index pairs, with the two faces that meet there.
EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)
                  if np.sum(CORNER_SIGNS[a] != CORNER_SIGNS[b]) == 1])
EDGE_FACES = np.array([[f for f in range(6) if a in FACES[f] and b in FACES[f]] for a, b in EDGES])


@dataclass(frozen=True)
class SpongeBox:
    """Sponge dimensions, metres."""

    length: float = 0.110  # along the sponge's x
    width: float = 0.075   # along y
    height: float = 0.030  # along z

    def __post_init__(self):
        if min(self.length, self.width, self.height) <= 0:
            raise ValueError("sponge dimensions must be positive")

    @property
    def half_extents(self) -> np.ndarray:
        """(length, width, height) / 2, shape (3,)."""
        return 0.5 * np.array([self.length, self.width, self.height])

    def corners(self) -> np.ndarray:
        """Corners in the sponge frame, shape (8, 3), indexed as :data:`CORNER_SIGNS`."""
        return CORNER_SIGNS * self.half_extents


def yaw_rotation(yaw: np.ndarray) -> np.ndarray:
    """Rotations about z, shape (..., 3, 3), for angles ``yaw`` (rad) of shape (...)."""
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.zeros(np.shape(yaw) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


def visible_faces(face_centres: np.ndarray, face_normals: np.ndarray,
                  eye: np.ndarray) -> np.ndarray:
    """Which faces turn towards a viewpoint (back-face test), bool array of shape (...).

    Parameters
    ----------
    face_centres, face_normals : ndarray, shape (..., 3)
        In one frame, with ``eye`` (3,) the camera centre in the same frame.
    """
    return np.einsum("...i,...i->...", face_normals, eye - face_centres) > 0.0
