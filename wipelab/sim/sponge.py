"""The sponge in the right hand: its passive compliance and the grasp the controller does not know.

The sponge is a box on a spring along its own z axis (a kitchen sponge is roughly
500-2000 N/m). The grasp, where the sponge sits relative to the TCP, is set by the simulator
and never told to the controller (the paper's reason for the ~5 cm height change per period on
a flat table). It is given relative to a *reference hand orientation* R_ref (the TCP's
orientation when the arm is at the centre of the task): with the hand at R_ref the sponge's
centre is at ``offset`` (world axes) from the TCP and its bottom face is tilted by ``tilt``
from level. As the hand's orientation changes along the path, so does the sponge's height.

Pure numpy: the geometry here also gives the true contact height for the metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wipelab.rotations import rotation_about_axis

#: Accepted sponge stiffness range (N/m): a kitchen sponge.
STIFFNESS_RANGE = (500.0, 2000.0)


@dataclass(frozen=True)
class SpongeParams:
    """The sponge and its passive compliance."""

    size: tuple[float, float, float] = (0.10, 0.07, 0.04)  # m: length (x), width (y), thickness (z)
    stiffness: float = 1000.0                                # N/m along the sponge's z axis
    damping_ratio: float = 0.8                               # of the spring-mass (dimensionless)
    mass: float = 0.08                                       # kg (a damp kitchen sponge)
    max_compression: float = 0.025                           # m before it bottoms out

    def __post_init__(self):
        low, high = STIFFNESS_RANGE
        if not low <= self.stiffness <= high:
            raise ValueError(f"sponge stiffness must be in [{low:g}, {high:g}] N/m, "
                             f"got {self.stiffness:g}")
        if min(self.size) <= 0 or self.mass <= 0 or self.damping_ratio < 0:
            raise ValueError("sponge size and mass must be > 0, damping ratio >= 0")

    @property
    def damping(self) -> float:
        """Damping coefficient c = 2 zeta sqrt(k m) (N s/m)."""
        return 2.0 * self.damping_ratio * math.sqrt(self.stiffness * self.mass)


@dataclass(frozen=True)
class Grasp:
    """Where the sponge sits in the hand (unknown to the controller).

    ``offset``: sponge centre minus TCP (m, the platform's axes) with the hand at R_ref;
    ``tilt``: (roll, pitch) in rad of the sponge about the platform's x and y axes with the
    hand at R_ref.
    """

    offset: tuple[float, float, float] = (0.04, 0.12, -0.09)
    tilt: tuple[float, float] = (-0.15, 0.10)


def tcp_to_sponge(grasp: Grasp, reference_rotation: np.ndarray, yaw: float = 0.0
                  ) -> np.ndarray:
    """Pose (4, 4) of the sponge frame (at rest, uncompressed) in the TCP frame, the grasp's
    offset and tilt turned by the platform's ``yaw`` (rad): the robot holds the sponge the
    same way whichever way it faces."""
    roll, pitch = grasp.tilt
    turn = rotation_about_axis(np.array([0.0, 0.0, 1.0]), yaw)
    level = turn @ (rotation_about_axis(np.array([1.0, 0.0, 0.0]), roll)
                    @ rotation_about_axis(np.array([0.0, 1.0, 0.0]), pitch))
    pose = np.eye(4)
    pose[:3, :3] = reference_rotation.T @ level
    pose[:3, 3] = reference_rotation.T @ turn @ np.asarray(grasp.offset, dtype=float)
    return pose


def bottom_points(size, samples: tuple[int, int] = (6, 5)) -> np.ndarray:
    """Points (k, 3) on the sponge's bottom face (sponge frame, m), edges included."""
    sx, sy, sz = size
    gx, gy = np.meshgrid(np.linspace(-sx / 2, sx / 2, samples[0]),
                         np.linspace(-sy / 2, sy / 2, samples[1]), indexing="ij")
    return np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, -sz / 2)], axis=1)


def collision_spheres(size, radius: float = 0.008, grid: tuple[int, int] = (5, 4)) -> np.ndarray:
    """Centres (k, 3) (sponge frame, m) of the spheres that make the sponge's collision shape:
    a grid over the bottom face whose lowest points lie on it. Spheres slide over triangle
    meshes and heightfields without the spurious deep contacts a box's corners produce."""
    sx, sy, sz = size
    gx, gy = np.meshgrid(np.linspace(-sx / 2 + radius, sx / 2 - radius, grid[0]),
                         np.linspace(-sy / 2 + radius, sy / 2 - radius, grid[1]), indexing="ij")
    return np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, -sz / 2 + radius)], axis=1)


def touch(height_at, tcp_xy: np.ndarray, tcp_rotation: np.ndarray, tcp_from_sponge: np.ndarray,
          size, radius: float = 0.008) -> tuple[np.ndarray, np.ndarray]:
    """TCP height (m, world) at which the uncompressed sponge first touches the surface, and
    the surface normal where it touches.

    The sponge touches with its collision spheres (:func:`collision_spheres`): a sphere of
    radius r whose centre is above surface point s with slope grad s touches when its centre
    is r sqrt(1 + |grad s|^2) above it (the surface taken as locally planar).

    Parameters
    ----------
    height_at : callable
        True surface height (m) at world points (..., 2).
    tcp_xy : array, shape (n, 2)
        TCP x, y (m, world).
    tcp_rotation : array, shape (n, 3, 3)
        TCP orientation in the world.
    tcp_from_sponge : array, shape (4, 4)
        Sponge pose in the TCP frame (:func:`tcp_to_sponge`).
    size : (3,)
        Sponge size (m).
    radius : float
        Radius of the collision spheres (m).

    Returns
    -------
    height : ndarray, shape (n,)
        The lowest TCP z at which no sphere is below the surface.
    normal : ndarray, shape (n, 3)
        Unit upward surface normal (world) under the sphere that touches first.
    """
    centres = collision_spheres(size, radius) @ tcp_from_sponge[:3, :3].T + tcp_from_sponge[:3, 3]
    world = np.einsum("nij,kj->nki", np.asarray(tcp_rotation), centres)           # (n, k, 3)
    xy = np.asarray(tcp_xy)[:, None, :] + world[..., :2]
    step = 0.002
    gx = (height_at(xy + [step, 0.0]) - height_at(xy - [step, 0.0])) / (2 * step)
    gy = (height_at(xy + [0.0, step]) - height_at(xy - [0.0, step])) / (2 * step)
    clearance = radius * np.sqrt(1.0 + gx ** 2 + gy ** 2)
    heights = height_at(xy) + clearance - world[..., 2]
    first = np.argmax(heights, axis=1)[:, None]
    slope = np.column_stack([-np.take_along_axis(gx, first, 1), -np.take_along_axis(gy, first, 1),
                             np.ones((len(heights), 1))])
    return np.max(heights, axis=1), slope / np.linalg.norm(slope, axis=1, keepdims=True)
