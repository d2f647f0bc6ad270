"""Where the right arm reaches, relative to the platform: a precomputed reachability map.

For a grid of TCP positions in the ``base_link`` frame and each torso lean the posture
search tries (:data:`~wipelab.sim.arm.HIP_PITCHES`), the arm alone is solved from its
comfortable seed posture as :meth:`~wipelab.sim.arm.RightArm.posture_for` solves the centre
of a task (position only, torso held), and the map keeps

- ``margin``: the smallest distance (rad) of an arm joint from its limits at the solution,
  or -1 where the IK misses the point by more than :data:`~wipelab.sim.arm.REACH_TOLERANCE`;
- ``inverse``: the joint velocities per unit horizontal TCP velocity there (rad/m, 7 x 2:
  the IK's weighted pseudo-inverse for x and y, as the tracker's feed-forward): a movement
  at velocity v (base_link x, y) asks |inverse @ v| of the joints. Stored as int8 in steps of
  :data:`INVERSE_STEP`; 0 where out of reach.

The placement search (:mod:`~wipelab.sim.placement`) screens thousands of placements with it
in milliseconds; the chosen one is then checked with the full IK. The map is package data
(``assets/reach_map.npz``), written by ``python -m wipelab.sim.reach`` (about a minute and a
half); a test recomputes some of its cells.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from wipelab.sim.arm import ARM_SEED, HIP_PITCHES, REACH_TOLERANCE, RightArm
from wipelab.sim.ik import ArmIK

#: The grid of TCP positions (m, base_link): first point, step and count per axis.
GRID_START = (0.16, -0.84, 0.48)
GRID_STEP = 0.04
GRID_SHAPE = (22, 28, 22)
#: IK iterations per cell (as posture_for's centre solve).
CELL_ITERATIONS = 300
#: Resolution (rad/m) of the stored pseudo-inverse.
INVERSE_STEP = 0.05


@dataclass(frozen=True)
class ReachMap:
    """Arm reach by torso lean and TCP position (see the module docstring).

    Attributes
    ----------
    pitches : ndarray (P,)
        Hip pitch of each layer (rad; negative leans forward), upright first.
    start : ndarray (3,)
        base_link position (m) of cell (0, 0, 0); ``step`` (m) apart.
    margin : ndarray (P, nx, ny, nz)
        Joint margin (rad); -1 where the point is out of reach.
    inverse : ndarray (P, nx, ny, nz, 7, 2)
        Joint velocity per horizontal TCP velocity (rad/m); 0 where out of reach.
    """

    pitches: np.ndarray
    start: np.ndarray
    step: float
    margin: np.ndarray
    inverse: np.ndarray

    def cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest cell index (..., 3) of base_link points (..., 3) (m), clipped to the
        grid, and whether each point lies inside the grid (...)."""
        position = (np.asarray(points, dtype=float) - self.start) / self.step
        index = np.rint(position).astype(int)
        shape = np.array(self.margin.shape[1:])
        inside = np.all((index >= 0) & (index < shape), axis=-1)
        return np.clip(index, 0, shape - 1), inside

    def margins(self, points: np.ndarray) -> np.ndarray:
        """Margin (P, ...) at the nearest cell of each base_link point (..., 3); -1 outside
        the grid."""
        index, inside = self.cells(points)
        return np.where(inside, self.margin[:, index[..., 0], index[..., 1], index[..., 2]],
                        -1.0)

    def inverses(self, points: np.ndarray) -> np.ndarray:
        """Pseudo-inverse (P, ..., 7, 2) at the nearest cell of each base_link point
        (..., 3); 0 outside the grid."""
        index, inside = self.cells(points)
        return (self.inverse[:, index[..., 0], index[..., 1], index[..., 2]]
                * inside[..., None, None])


def grid_points() -> np.ndarray:
    """base_link TCP positions (nx, ny, nz, 3) (m) of the map's cells."""
    axes = [GRID_START[a] + GRID_STEP * np.arange(GRID_SHAPE[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)


def cell_ik(pitch: float) -> ArmIK:
    """The IK the map's cells are solved with: the arm with the hip leaning ``pitch`` (rad),
    the platform at the origin."""
    return RightArm({}).arm_ik(np.array([pitch, 0.0, 0.0]), ARM_SEED)


def reach_cell(ik: ArmIK, point) -> tuple[float, np.ndarray]:
    """Margin (rad; -1 out of reach) and pseudo-inverse (7, 2) (rad/m; 0 out of reach) of
    one base_link point (3,) for the IK of :func:`cell_ik`."""
    q, error = ik.solve(ARM_SEED, np.asarray(point, dtype=float),
                        max_iterations=CELL_ITERATIONS)
    if error > REACH_TOLERANCE:
        return -1.0, np.zeros((len(q), 2))
    margin = float(np.min(np.minimum(q - ik.chain.lower, ik.chain.upper - q)))
    return margin, np.column_stack([ik.joint_velocity(q, axis) for axis in np.eye(3)[:2]])


def compute_reach_map(progress=None) -> ReachMap:
    """Solve every cell (see the module docstring); ``progress(done, total)`` is called
    after each torso lean."""
    points = grid_points().reshape(-1, 3)
    margin = np.empty((len(HIP_PITCHES), len(points)))
    inverse = np.empty((len(HIP_PITCHES), len(points), 7, 2))
    for p, pitch in enumerate(HIP_PITCHES):
        ik = cell_ik(float(pitch))
        for c, point in enumerate(points):
            margin[p, c], inverse[p, c] = reach_cell(ik, point)
        if progress is not None:
            progress(p + 1, len(HIP_PITCHES))
    shape = (len(HIP_PITCHES), *GRID_SHAPE)
    return ReachMap(np.asarray(HIP_PITCHES, dtype=float), np.array(GRID_START), GRID_STEP,
                    margin.reshape(shape), quantised(inverse.reshape(*shape, 7, 2)))


def quantised(inverse: np.ndarray) -> np.ndarray:
    """The pseudo-inverse as the map stores it: rounded to INVERSE_STEP (int8 range)."""
    return np.clip(np.rint(inverse / INVERSE_STEP), -127, 127) * INVERSE_STEP


def reach_map_path() -> Path:
    """Path of the shipped map (package data)."""
    return Path(str(resources.files("wipelab.sim") / "assets" / "reach_map.npz"))


def save_reach_map(reach: ReachMap, path: Path) -> None:
    """Write a map as a compressed .npz (margin float32, inverse int8)."""
    np.savez_compressed(path, pitches=reach.pitches, start=reach.start,
                        step=np.array(reach.step), margin=reach.margin.astype(np.float32),
                        inverse=np.rint(reach.inverse / INVERSE_STEP).astype(np.int8))


@lru_cache(maxsize=1)
def load_reach_map() -> ReachMap:
    """The shipped map."""
    with np.load(reach_map_path()) as data:
        return ReachMap(data["pitches"], data["start"], float(data["step"]),
                        data["margin"].astype(float), data["inverse"] * INVERSE_STEP)


if __name__ == "__main__":
    def _progress(done: int, total: int) -> None:
        print(f"torso lean {done}/{total}", file=sys.stderr)

    save_reach_map(compute_reach_map(_progress), reach_map_path())
    print(f"wrote {reach_map_path()} ({math.prod(GRID_SHAPE)} cells x {len(HIP_PITCHES)} leans)")
