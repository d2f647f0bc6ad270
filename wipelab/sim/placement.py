"""Where the path goes on the surface and where the platform stands: the placement search.

ARMAR-IIIb stands on a holonomic platform, so a wiping movement can be done anywhere the
platform can get close enough to. :func:`choose_placements` searches where the centre of the
path's bounding box goes on the surface (``centre``) and how the platform stands (``base``:
x, y, yaw) and ranks the placements that pass every screen:

- on the surface: the sponge (its rectangle around the sponge centre, which sits at the grasp
  offset from the TCP, turned with the platform) stays :data:`SURFACE_MARGIN` inside the
  surface's footprint all along the path;
- the platform clear of the surface: its box, grown by :data:`PLATFORM_CLEARANCE`, does not
  overlap the footprint (a table or counter stands on the floor under its top);
- within reach: every path point, at the height where the sponge touches the surface (the TCP
  :data:`NOMINAL_TOOL_DROP` above it, +-:data:`REACH_BAND`), is reached by the arm with the
  joint margin :data:`~wipelab.sim.arm.LIMIT_MARGIN` for one torso lean
  (:class:`~wipelab.sim.reach.ReachMap`).

Score (higher is better): how much of :data:`TARGET_TEMPO` x the demonstrated tempo the arm's
joint speeds allow (the map's pseudo-inverse times the path's velocity), up to it, counts 2;
the joint margin up to :data:`GOOD_MARGIN` counts 1; every :data:`CENTRE_SCALE` of distance
from the preferred centre (a surface's declared wiping centre; :data:`LOOSE_CENTRE_SCALE` when
it only is the middle of the surface) costs 1 and every 90 degrees of platform yaw away from
the preferred yaw 0.5 (the robot faces the surface the way the user put it).

The placement is relative: the arm's part of the score depends only on where the path lies
relative to the platform (``offset``: the path centre in the platform's frame) and the yaw;
candidates combine every centre on a :data:`CENTRE_STEP` grid of the surface with every
offset on an :data:`OFFSET_STEP` grid and every yaw of :data:`YAWS`, and the platform stands
at centre - R(yaw) offset. Everything is numpy over arrays; the caller checks the best ones
with the full IK (:func:`~wipelab.sim.task.plan_task`).

When no placement passes, :class:`PlacementError` names what limits it: the surface too small
for the path and the sponge, the surface out of the arm's height range, or the platform
unable to get close enough.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from wipelab.sim.arm import LIMIT_MARGIN
from wipelab.sim.armar3 import PLATFORM_SIZE
from wipelab.sim.reach import ReachMap
from wipelab.sim.surfaces import Surface
from wipelab.sim.world import BasePose

#: How far below the TCP the operator assumes the sponge's bottom to be (m), for choosing the
#: posture; the true grasp is not used.
NOMINAL_TOOL_DROP = 0.11
#: Height band (m) around the nominal contact height that the posture must reach.
REACH_BAND = 0.04
#: Where the operator assumes the sponge's centre to be (m, platform axes, from the TCP) for
#: keeping it on the surface; the true grasp is not used.
NOMINAL_SPONGE_OFFSET = (0.04, 0.12)
#: Smallest distance (m) of the sponge's edge from the edge of the surface in the screen: the
#: hand turns a little along the path, which the screen does not know (the full check does,
#: with SPONGE_MARGIN).
SURFACE_MARGIN = 0.03
SPONGE_MARGIN = 0.01
#: Gap (m) kept between the platform's box and the surface's footprint.
PLATFORM_CLEARANCE = 0.03
#: Grid step (m) of the candidate path centres on the surface.
CENTRE_STEP = 0.03
#: Candidate path centres in the platform's frame: x and y ranges (m) and step.
OFFSET_X = (0.30, 0.86)
OFFSET_Y = (-0.60, 0.08)
OFFSET_STEP = 0.05
#: Candidate platform yaws relative to the preferred one (rad), in order of preference.
YAWS = np.radians([0.0, -20.0, 20.0, -45.0, 45.0, -90.0, 90.0])
#: Path samples used by the screens.
PATH_SAMPLES = 16
#: The tempo (x the demonstrated one) the placement should leave the arm fast enough for.
TARGET_TEMPO = 1.5
#: Joint margin (rad) beyond which more margin does not raise the score.
GOOD_MARGIN = math.radians(15.0)
#: Distance (m) from the preferred centre that costs as much as the whole margin term.
CENTRE_SCALE = 0.2
#: The same when the preferred centre is only the middle of the surface (a tie-breaker).
LOOSE_CENTRE_SCALE = 2.0
#: Platform positions (m; yaw counts 0.2 m per rad) closer than this are near-copies.
DIVERSITY = 0.08


class PlacementError(Exception):
    """No placement passes the screens; the message says what limits it."""


@dataclass(frozen=True)
class PlacementRequest:
    """What is placed.

    Attributes
    ----------
    path : ndarray (n, 2)
        TCP path (m, world axes) relative to the centre of its bounding box, in phase order.
    velocity : ndarray (n, 2)
        d path / d phase (m/rad).
    frequency_hz : float
        The demonstrated tempo.
    sponge_offset : ndarray (2,)
        Sponge centre minus TCP (m, platform axes) with the hand at the task's posture.
    sponge_size : ndarray (2,)
        The sponge's length and width (m), along the platform's x and y.
    preferred_centre : ndarray (2,)
        Where the path should go if the robot can do it there (m, world).
    preferred_yaw : float
        Platform yaw (rad) the robot should rather have.
    centre_scale : float
        Distance (m) from ``preferred_centre`` that costs 1 (CENTRE_SCALE or
        LOOSE_CENTRE_SCALE).
    centre : ndarray (2,) or None
        A fixed path centre (``--center``).
    base : BasePose or None
        A fixed platform pose (``--base``).
    """

    path: np.ndarray
    velocity: np.ndarray
    frequency_hz: float
    sponge_offset: np.ndarray
    sponge_size: np.ndarray
    preferred_centre: np.ndarray
    preferred_yaw: float = 0.0
    centre_scale: float = CENTRE_SCALE
    centre: np.ndarray | None = None
    base: BasePose | None = None


@dataclass(frozen=True)
class Placement:
    """A placement that passed the screens, with what the reach map predicts for it."""

    centre: np.ndarray         # (2,) m, world: where the path's bounding-box centre goes
    base: BasePose             # the platform pose
    hip_pitch: float           # rad: the torso lean the map found (negative: forward)
    margin: float              # rad: the smallest joint margin along the path (map)
    max_frequency_hz: float    # the fastest tempo the map's joint speeds allow
    score: float

    def describe(self) -> dict:
        """JSON-ready record."""
        return {"center": [float(v) for v in self.centre],
                "base": [self.base.x, self.base.y, self.base.yaw],
                "hip_pitch_rad": self.hip_pitch, "joint_margin_rad": self.margin,
                "max_frequency_hz": self.max_frequency_hz}


def _rotation(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class _Grid:
    """A boolean raster on a :data:`CENTRE_STEP` grid: cell (i, j) at origin + step (i, j)."""

    origin: np.ndarray
    mask: np.ndarray

    def points(self) -> np.ndarray:
        """World x-y (nx, ny, 2) of the cells."""
        axes = [self.origin[a] + CENTRE_STEP * np.arange(self.mask.shape[a]) for a in range(2)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def at(self, points: np.ndarray, outside: bool = False) -> np.ndarray:
        """The mask at the nearest cell of world points (..., 2); ``outside`` beyond it."""
        nx, ny = self.mask.shape
        i = np.rint((points[..., 0] - self.origin[0]) * (1.0 / CENTRE_STEP)).astype(int)
        j = np.rint((points[..., 1] - self.origin[1]) * (1.0 / CENTRE_STEP)).astype(int)
        inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        return np.where(inside, self.mask.ravel()[np.clip(i, 0, nx - 1) * ny
                                                  + np.clip(j, 0, ny - 1)], outside)


def _footprint(surface: Surface) -> _Grid:
    """The surface's footprint resampled on the CENTRE_STEP grid (nearest grid point)."""
    extent = (np.array(surface.heights.shape) - 1) * surface.cell
    shape = np.floor(extent / CENTRE_STEP + 1e-9).astype(int) + 1
    origin = surface.origin[:2] + (extent - (shape - 1) * CENTRE_STEP) / 2
    grid = _Grid(origin, np.zeros(shape, dtype=bool))
    index = np.rint((grid.points() - surface.origin[:2]) / surface.cell).astype(int)
    return _Grid(origin, surface.covered()[index[..., 0], index[..., 1]])


def _raster(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cells of the CENTRE_STEP grid (relative to (0, 0)) covered by points (k, 2) (m): a
    kernel (kx, ky) bool and the index of the (0, 0) offset in it (the kernel spans it even
    when no point is there)."""
    index = np.rint(points / CENTRE_STEP).astype(int)
    low = np.minimum(index.min(axis=0), 0)
    kernel = np.zeros(np.maximum(index.max(axis=0), 0) - low + 1, dtype=bool)
    kernel[index[:, 0] - low[0], index[:, 1] - low[1]] = True
    return kernel, -low


def _overlap(grid: _Grid, kernel: np.ndarray, centre: np.ndarray, pad: int) -> _Grid:
    """How many cells of ``kernel`` (its (0, 0) offset at ``centre``) fall on the mask, for
    the kernel placed at every cell of the grid grown by ``pad`` cells on each side: a
    correlation by FFT. Returned as a grid whose mask is "overlap > 0"."""
    nx, ny = grid.mask.shape
    size = (nx + 2 * pad + kernel.shape[0], ny + 2 * pad + kernel.shape[1])
    field = np.zeros(size)
    field[pad + centre[0]:pad + centre[0] + nx, pad + centre[1]:pad + centre[1] + ny] = grid.mask
    counts = np.fft.irfft2(np.fft.rfft2(field) * np.conj(np.fft.rfft2(kernel.astype(float),
                                                                     size)), size)
    counts = counts[:nx + 2 * pad, :ny + 2 * pad]
    return _Grid(grid.origin - pad * CENTRE_STEP, counts > 0.5)


def sponge_outline(offset: np.ndarray, size: np.ndarray, yaw: float,
                   margin: float = SURFACE_MARGIN) -> np.ndarray:
    """Points (k, 2) (m, world axes, relative to the TCP) covering the sponge grown by
    ``margin`` (m), every CENTRE_STEP / 2: its centre ``offset`` (2,) and ``size`` (2,) in
    the axes of a platform turned by ``yaw``."""
    half = np.asarray(size) / 2 + margin
    axes = [np.linspace(-h, h, int(math.ceil(2 * h / (CENTRE_STEP / 2))) + 1) for h in half]
    local = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 2)
    return (np.asarray(offset) + local) @ _rotation(yaw).T


def _sponge_swept(request: PlacementRequest, yaw: float) -> np.ndarray:
    """Points (k, 2) (m, world axes, relative to the path centre) the sponge covers along
    the path."""
    shape = sponge_outline(request.sponge_offset, request.sponge_size, yaw)
    return (request.path[:, None, :] + shape[None]).reshape(-1, 2)


def platform_outline(base: BasePose, clearance: float = PLATFORM_CLEARANCE) -> np.ndarray:
    """Points (k, 2) (m, world) covering the platform's box at ``base`` grown by
    ``clearance``, every CENTRE_STEP / 2."""
    half = PLATFORM_SIZE[0] / 2 + clearance
    axis = np.linspace(-half, half, int(math.ceil(2 * half / (CENTRE_STEP / 2))) + 1)
    local = np.stack(np.meshgrid(axis, axis, indexing="ij"), axis=-1).reshape(-1, 2)
    return local @ _rotation(base.yaw).T + [base.x, base.y]


def _samples(request: PlacementRequest) -> PlacementRequest:
    """The request with its path reduced to PATH_SAMPLES points."""
    pick = np.linspace(0, len(request.path), PATH_SAMPLES, endpoint=False).astype(int)
    return replace(request, path=request.path[pick], velocity=request.velocity[pick])


def _offsets() -> np.ndarray:
    """Candidate path centres in the platform's frame (k, 2) (m)."""
    x = np.arange(OFFSET_X[0], OFFSET_X[1] + 1e-9, OFFSET_STEP)
    y = np.arange(OFFSET_Y[0], OFFSET_Y[1] + 1e-9, OFFSET_STEP)
    return np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1).reshape(-1, 2)


def _arm_screen(request: PlacementRequest, reach: ReachMap, yaw: float, offsets: np.ndarray,
                height: float, band: float, joint_speed_limit: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Torso lean index (-1: none reaches), joint margin (rad) and fastest tempo (Hz) for
    each offset (k, 2) at one yaw: every path point reached at the contact ``height`` (m,
    world z) +- ``band`` (m); the tempo from the map's pseudo-inverse at the path's points.

    The base_link frame has the platform's yaw and its origin on the floor, so a point's
    base_link z is its world z.
    """
    turn = _rotation(yaw)
    relative, velocity = request.path @ turn, request.velocity @ turn   # R(yaw)^T: (n, 2)
    n = len(relative)
    xy = np.broadcast_to(offsets[:, None, :] + relative[None], (len(offsets), n, 2))
    points = np.concatenate([np.concatenate([xy, np.full((len(offsets), n, 1), z)], axis=-1)
                             for z in height + NOMINAL_TOOL_DROP + np.array([0.0, -band, band])],
                            axis=1)                              # (k, 3n, 3)
    worst = reach.margins(points).min(axis=2)                    # (P, k)
    joint_rate = np.abs(np.einsum("pknjd,nd->pknj", reach.inverses(points[:, :n]),
                                  velocity)).max(axis=(2, 3))   # (P, k): rad per rad of phase
    good = worst >= LIMIT_MARGIN
    lean = np.where(good.any(axis=0), np.argmax(good, axis=0), -1)
    pick, columns = np.maximum(lean, 0), np.arange(len(offsets))
    rate = joint_rate[pick, columns]
    fastest = np.where(lean < 0, 0.0, np.where(rate > 0, joint_speed_limit
                                               / np.maximum(rate, 1e-12), np.inf))
    return lean, worst[pick, columns], fastest / (2.0 * math.pi)


def choose_placements(request: PlacementRequest, surface: Surface, reach: ReachMap,
                      joint_speed_limit: float, count: int = 5) -> list[Placement]:
    """The ``count`` best placements (see the module docstring), best first.

    Parameters
    ----------
    request : PlacementRequest
    surface : Surface
    reach : ReachMap
    joint_speed_limit : float
        rad/s a planned movement may ask of a joint.

    Raises
    ------
    PlacementError
        None passes the screens; the message says which screen stopped them.
    """
    request = _samples(request)
    footprint = _footprint(surface)
    if request.centre is not None:
        centres = np.asarray(request.centre, dtype=float).reshape(1, 2)
    else:
        preferred = np.asarray(request.preferred_centre, dtype=float).reshape(1, 2)
        grid = footprint.points().reshape(-1, 2)
        grid = grid[np.linalg.norm(grid - preferred, axis=1) > 1e-6]
        centres = np.concatenate([preferred, grid])
    contact = surface.height_at(centres[:, None, :] + request.path[None])      # (C, n)
    defined = ~np.isnan(contact).any(axis=1)
    centres, contact = centres[defined], contact[defined]
    # the contact heights on the reach map's grid: a mean height and a band that covers them
    level = np.rint((contact.mean(axis=1) - reach.start[2] + NOMINAL_TOOL_DROP) / reach.step)
    band = np.maximum(REACH_BAND, np.ceil((np.ptp(contact, axis=1) / 2 + 0.01) / reach.step)
                      * reach.step)
    yaws = (np.array([request.base.yaw]) if request.base is not None
            else request.preferred_yaw + YAWS)
    target_hz = TARGET_TEMPO * request.frequency_hz
    distance = np.linalg.norm(centres - request.preferred_centre, axis=1)
    offsets = _offsets()
    pad = int(math.ceil((np.linalg.norm(OFFSET_X + OFFSET_Y) + PLATFORM_SIZE[0])
                        / CENTRE_STEP))
    found: list[tuple[float, Placement]] = []
    passed = {"surface": 0, "platform": 0, "reach": 0}
    for yaw in yaws:
        kernel, origin = _raster(_sponge_swept(request, yaw))
        border = max(kernel.shape)                     # beyond the grid: no surface either
        outside = _Grid(footprint.origin - border * CENTRE_STEP,
                        np.pad(~footprint.mask, border, constant_values=True))
        fits = ~_overlap(outside, kernel, origin, 0).at(centres, outside=True)
        passed["surface"] += int(fits.sum())
        platform = _overlap(footprint, *_raster(platform_outline(BasePose(yaw=yaw))), pad)
        rotation = _rotation(yaw)
        for key in np.unique(np.column_stack([level, band])[fits], axis=0):
            group = np.flatnonzero(fits & (level == key[0]) & (band == key[1]))
            height = reach.start[2] + key[0] * reach.step - NOMINAL_TOOL_DROP
            if request.base is not None:     # the offsets follow from the fixed platform
                base = np.array([request.base.x, request.base.y])
                candidates = (centres[group] - base) @ rotation            # R^T (c - b)
                passed["platform"] += len(group)
                lean, margin, fastest = _arm_screen(request, reach, yaw, candidates, height,
                                                    key[1], joint_speed_limit)
                rows = np.flatnonzero(lean >= 0)
                bases = np.broadcast_to(base, (len(rows), 2))
                lean, margin, fastest, group = lean[rows], margin[rows], fastest[rows], \
                    group[rows]
            else:
                bases = centres[group][:, None, :] - (offsets @ rotation.T)[None]   # (g, K, 2)
                clear = ~platform.at(bases)
                passed["platform"] += int(clear.sum())
                usable = np.flatnonzero(clear.any(axis=0))
                if not len(usable):
                    continue
                lean, margin, fastest = _arm_screen(request, reach, yaw, offsets[usable],
                                                    height, key[1], joint_speed_limit)
                rows, columns = np.nonzero(clear[:, usable] & (lean >= 0)[None])
                bases = bases[rows, usable[columns]]
                lean, margin, fastest = lean[columns], margin[columns], fastest[columns]
                group = group[rows]
            passed["reach"] += len(group)
            if not len(group):
                continue
            score = (2.0 * np.minimum(fastest / target_hz, 1.0)
                     + np.minimum(margin, GOOD_MARGIN) / GOOD_MARGIN
                     - distance[group] / request.centre_scale
                     - 0.5 * abs(yaw - request.preferred_yaw) / (math.pi / 2))
            for k in _diverse(np.argsort(-score, kind="stable"), bases[:, :2], count):
                found.append((float(score[k]), Placement(
                    centres[group[k]].copy(), BasePose(float(bases[k][0]), float(bases[k][1]),
                                                       float(yaw)),
                    float(reach.pitches[lean[k]]), float(margin[k]), float(fastest[k]),
                    float(score[k]))))
    if not found:
        raise PlacementError(_limit_message(request, surface, reach, passed))
    found.sort(key=lambda item: -item[0])
    ranked = [placement for _, placement in found]
    bases = np.array([[p.base.x, p.base.y, 0.2 * p.base.yaw] for p in ranked])
    return [ranked[k] for k in _diverse(np.arange(len(ranked)), bases, count)]


def _diverse(order: np.ndarray, positions: np.ndarray, count: int) -> list[int]:
    """Up to ``count`` indices of ``order`` (best first) whose ``positions`` (rows) are at
    least DIVERSITY apart, then the rest in order: the full check then tries different
    ways to stand before near-copies of a rejected one."""
    chosen: list[int] = []
    for k in order:
        apart = positions[chosen] - positions[k]
        if np.all(np.einsum("ij,ij->i", apart, apart) >= DIVERSITY ** 2):
            chosen.append(int(k))
            if len(chosen) == count:
                return chosen
    rest = [int(k) for k in order if int(k) not in chosen]
    return chosen + rest[:count - len(chosen)]


def _limit_message(request: PlacementRequest, surface: Surface, reach: ReachMap,
                   limits: dict) -> str:
    """What stopped every placement, in words."""
    size = np.ptp(request.path, axis=0) * 100
    if not limits["surface"]:
        where = "there" if request.centre is not None else "anywhere on it"
        return (f"the movement ({size[0]:.0f} x {size[1]:.0f} cm, with the sponge) does not "
                f"fit on the surface {surface.name!r} {where}")
    if not limits["platform"]:
        return (f"the platform cannot stand close enough to the movement on the surface "
                f"{surface.name!r}: wherever the movement ({size[0]:.0f} x {size[1]:.0f} cm) "
                f"fits, it is more than {OFFSET_X[1]:.2f} m ahead of the platform's centre")
    heights = surface.heights[surface.covered()] + surface.origin[2]
    low, high = _reach_heights(reach)
    return (f"the arm cannot reach the movement ({size[0]:.0f} x {size[1]:.0f} cm) on the "
            f"surface {surface.name!r} ({heights.min():.2f}-{heights.max():.2f} m high; the "
            f"arm wipes surfaces {low:.2f}-{high:.2f} m high, movements up to about 40 cm "
            f"across)")


def _reach_heights(reach: ReachMap) -> tuple[float, float]:
    """Surface heights (m) where the arm reaches some point with margin (the TCP range of
    the map minus the tool drop)."""
    good = (reach.margin >= LIMIT_MARGIN).any(axis=(0, 1, 2))
    z = reach.start[2] + reach.step * np.flatnonzero(good)
    return (float(z.min() + REACH_BAND - NOMINAL_TOOL_DROP),
            float(z.max() - REACH_BAND - NOMINAL_TOOL_DROP))
