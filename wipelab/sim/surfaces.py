"""Surfaces to wipe: built-in ``flat`` / ``bowl`` / ``sink`` and the user's heightfield or mesh.

Every surface is known to the simulator as a height grid in the world frame (DESIGN.md,
"Surfaces"): ``heights[i, j]`` (m) is the surface at ``x = origin_x + i * cell``,
``y = origin_y + j * cell``, world ``z = origin_z + heights[i, j]``. The grid gives the true
surface height anywhere (bilinear) for the metrics and, except for ``flat`` (a box, exact) and
``mesh`` (the OBJ itself), it is also the collision geometry (a triangle mesh through the
grid points).

Built-ins (all placed in front of ARMAR-IIIb standing at the origin facing +x; the table's
near edge at x = 0.40 m, as the platform reaches 0.35 m forward):

- ``flat``: a kitchen table top at ``height`` (default 0.80 m), optionally tilted by
  ``tilt_x`` / ``tilt_y`` (rad, rotation about the world x / y axis through ``wipe_center``).
- ``bowl``: a paraboloid basin of ``radius`` 0.22 m and ``depth`` 0.08 m (>= 0.06 m) sunk
  into a counter top at ``height`` 0.86 m, its centre 5 cm beyond the wiping centre in x,
  so that a circular wipe of 10 cm radius climbs up and down its side.
- ``sink``: a basin floor at ``height`` 0.80 m with a raised ``edge`` (0.02 m high, rising
  over ``edge_width`` 0.05 m) parallel to x at ``edge_y`` (0.07 m left of the wiping
  centre): a left-right wipe climbs over it (force-vector-length feedback, Sec. II-B).

A TOML file selects one of them with parameters (``type = "bowl"``, ``depth = 0.07``, ...)
or brings its own: ``type = "heightfield"`` with ``file`` (.npy, 2-D), ``cell`` (m) and
``origin = [x, y, z]``; ``type = "mesh"`` with ``file`` (.obj, metres, world frame, z up).
Any of them may set ``wipe_center = [x, y]`` (m, world) and ``friction`` (sponge-surface
Coulomb coefficient).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import read_input_npy, read_input_text, read_input_toml, reading

#: Names accepted by ``--surface`` besides a .toml file.
BUILTIN_SURFACES = ("flat", "bowl", "sink")
#: Default centre of the wiping movement (m, world x, y): in front of the right shoulder.
DEFAULT_WIPE_CENTER = (0.58, -0.28)
#: Table extent used by every built-in (m): x from 0.40 to 1.00, y from -0.70 to 0.30.
_TABLE_X = (0.40, 1.00)
_TABLE_Y = (-0.70, 0.30)
#: Bounds of a user's surface: grid points (a 10 m x 10 m mesh at 5 mm; the simulator builds
#: two triangles per point) and heights (m, from the origin or the world's z = 0).
MAX_GRID_POINTS = 4_000_000
MAX_HEIGHT = 10.0


@dataclass(frozen=True)
class Surface:
    """A surface in the world frame.

    Attributes
    ----------
    name : str
        ``flat``, ``bowl``, ``sink`` or the TOML file's stem.
    kind : str
        ``flat``, ``bowl``, ``sink``, ``heightfield`` or ``mesh``.
    heights : ndarray, shape (nx, ny)
        Height grid (m) above ``origin[2]``.
    cell : float
        Grid spacing (m).
    origin : ndarray, shape (3,)
        World position of ``heights[0, 0]``'s corner (m).
    wipe_center : ndarray, shape (2,)
        Default centre of the wiping movement (m, world x, y).
    friction : float
        Coulomb friction coefficient between sponge and surface.
    parameters : dict
        What defines it (for logs and the adapted model's ``surface`` entry).
    mesh_file : Path or None
        The OBJ file of a ``mesh`` surface (its collision geometry).
    tilt : tuple of float
        (about x, about y) in rad for ``flat`` (its collision box is rotated by them).
    footprint : ndarray (nx, ny) of bool, or None
        Where the grid has a surface (a mesh may not cover its bounding box); None: all of it.
    wipe_center_given : bool
        Whether ``wipe_center`` was chosen (a built-in's, a TOML's ``wipe_center``) or is only
        the middle of the grid.
    """

    name: str
    kind: str
    heights: np.ndarray
    cell: float
    origin: np.ndarray
    wipe_center: np.ndarray
    friction: float = 0.4
    parameters: dict = field(default_factory=dict)
    mesh_file: Path | None = None
    tilt: tuple[float, float] = (0.0, 0.0)
    footprint: np.ndarray | None = None
    wipe_center_given: bool = True

    def covered(self) -> np.ndarray:
        """Where the grid has a surface: bool (nx, ny)."""
        return (np.ones(self.heights.shape, dtype=bool) if self.footprint is None
                else self.footprint)

    def height_at(self, xy) -> np.ndarray:
        """True surface height (m, world z) at points ``xy`` (..., 2), bilinear on the grid;
        NaN outside it."""
        xy = np.asarray(xy, dtype=float)
        u = (xy[..., 0] - self.origin[0]) / self.cell
        v = (xy[..., 1] - self.origin[1]) / self.cell
        nx, ny = self.heights.shape
        inside = (u >= 0) & (u <= nx - 1) & (v >= 0) & (v <= ny - 1)
        i = np.clip(np.floor(u).astype(int), 0, nx - 2)
        j = np.clip(np.floor(v).astype(int), 0, ny - 2)
        a, b = np.clip(u - i, 0.0, 1.0), np.clip(v - j, 0.0, 1.0)
        h = self.heights
        z = ((1 - a) * (1 - b) * h[i, j] + a * (1 - b) * h[i + 1, j]
             + (1 - a) * b * h[i, j + 1] + a * b * h[i + 1, j + 1])
        return np.where(inside, z + self.origin[2], np.nan)

    def grid_points(self) -> np.ndarray:
        """World coordinates (nx, ny, 3) of the grid's points."""
        nx, ny = self.heights.shape
        x = self.origin[0] + self.cell * np.arange(nx)
        y = self.origin[1] + self.cell * np.arange(ny)
        gx, gy = np.meshgrid(x, y, indexing="ij")
        return np.stack([gx, gy, self.heights + self.origin[2]], axis=-1)

    def describe(self) -> dict:
        """JSON-ready description (name, kind, parameters)."""
        return {"name": self.name, "kind": self.kind, **self.parameters}


def _grid(cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Table-sized grid: origin (3,) at z = 0 and the world x (nx,), y (ny,) of its points."""
    nx = int(round((_TABLE_X[1] - _TABLE_X[0]) / cell)) + 1
    ny = int(round((_TABLE_Y[1] - _TABLE_Y[0]) / cell)) + 1
    x = _TABLE_X[0] + cell * np.arange(nx)
    y = _TABLE_Y[0] + cell * np.arange(ny)
    return np.array([_TABLE_X[0], _TABLE_Y[0], 0.0]), x, y


def flat_surface(height: float = 0.80, tilt_x: float = 0.0, tilt_y: float = 0.0,
                 wipe_center=DEFAULT_WIPE_CENTER, friction: float = 0.4,
                 cell: float = 0.01) -> Surface:
    """A table top at ``height`` (m) through ``wipe_center``, tilted by ``tilt_x``/``tilt_y``
    (rad; right-handed about world x / y): z = height + tan(tilt_y)(cx - x) + tan(tilt_x)(y - cy)."""
    origin, x, y = _grid(cell)
    cx, cy = wipe_center
    gx, gy = np.meshgrid(x, y, indexing="ij")
    heights = height - math.tan(tilt_y) * (gx - cx) + math.tan(tilt_x) * (gy - cy)
    return Surface("flat", "flat", heights, cell, origin, np.array(wipe_center, dtype=float),
                   friction, {"height": height, "tilt_x": tilt_x, "tilt_y": tilt_y},
                   tilt=(tilt_x, tilt_y))


def bowl_surface(height: float = 0.86, radius: float = 0.22, depth: float = 0.08,
                 center_offset=(0.05, 0.0), wipe_center=DEFAULT_WIPE_CENTER,
                 friction: float = 0.4, cell: float = 0.005) -> Surface:
    """A paraboloid basin z = height - depth (1 - (r / radius)^2) for r < radius in a counter
    top at ``height``; its centre at ``wipe_center + center_offset`` (m)."""
    if depth < 0.06:
        raise InputError(f"bowl: depth must be at least 0.06 m, got {depth}")
    origin, x, y = _grid(cell)
    bx, by = np.asarray(wipe_center, dtype=float) + np.asarray(center_offset, dtype=float)
    gx, gy = np.meshgrid(x, y, indexing="ij")
    r2 = ((gx - bx) ** 2 + (gy - by) ** 2) / radius ** 2
    heights = height - depth * np.clip(1.0 - r2, 0.0, None)
    return Surface("bowl", "bowl", heights, cell, origin, np.array(wipe_center, dtype=float),
                   friction, {"height": height, "radius": radius, "depth": depth,
                              "center": [float(bx), float(by)]})


def sink_surface(height: float = 0.80, edge: float = 0.02, edge_width: float = 0.05,
                 edge_y: float = 0.07, wipe_center=DEFAULT_WIPE_CENTER, friction: float = 0.4,
                 cell: float = 0.005) -> Surface:
    """A basin floor at ``height`` with a raised edge: for y > wipe_center_y + edge_y the
    surface is ``edge`` (m) higher, rising smoothly (cosine) over ``edge_width`` (m)."""
    origin, x, y = _grid(cell)
    y0 = wipe_center[1] + edge_y
    ramp = np.clip((y - y0) / edge_width, 0.0, 1.0)
    profile = edge * 0.5 * (1.0 - np.cos(math.pi * ramp))
    heights = height + np.broadcast_to(profile, (x.size, y.size)).copy()
    return Surface("sink", "sink", heights, cell, origin, np.array(wipe_center, dtype=float),
                   friction, {"height": height, "edge": edge, "edge_width": edge_width,
                              "edge_y": float(y0)})


_BUILDERS = {"flat": flat_surface, "bowl": bowl_surface, "sink": sink_surface}


def heightfield_surface(name: str, heights, cell: float, origin, wipe_center=None,
                        friction: float = 0.4, source: str = "heights") -> Surface:
    """A user height grid; validated (2-D, at least 2 x 2, finite; cell > 0)."""
    heights = np.asarray(heights)
    if heights.ndim != 2 or min(heights.shape) < 2 or heights.size > MAX_GRID_POINTS:
        raise InputError(f"{source}: heightfield must be a 2-D array of 2 x 2 to "
                         f"{MAX_GRID_POINTS:.0e} heights in metres, got shape {heights.shape}")
    if (heights.dtype.kind not in "iuf"
            or not np.all(np.isfinite(heights))):
        raise InputError(f"{source}: heightfield holds non-numeric, NaN or infinite values")
    if np.abs(heights).max() > MAX_HEIGHT:
        raise InputError(f"{source}: heightfield holds {np.abs(heights).max():g} m; heights are "
                         f"metres within +-{MAX_HEIGHT:g}")
    if not (isinstance(cell, (int, float)) and math.isfinite(cell) and cell > 0):
        raise InputError(f"{source}: cell must be a positive number of metres, got {cell!r}")
    origin = np.asarray(origin, dtype=float)
    if origin.shape != (3,) or not np.all(np.isfinite(origin)):
        raise InputError(f"{source}: origin must be [x, y, z] in metres, got {origin.tolist()}")
    heights = heights.astype(float)
    given = wipe_center is not None
    if not given:
        extent = (np.array(heights.shape) - 1) * cell
        wipe_center = origin[:2] + extent / 2
    return Surface(name, "heightfield", heights, float(cell), origin,
                   np.asarray(wipe_center, dtype=float), friction,
                   {"file": source, "cell": float(cell), "origin": origin.tolist(),
                    "shape": list(heights.shape)}, wipe_center_given=given)


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) and triangles (m, 3, int) of a Wavefront OBJ (polygons fanned).

    Raises
    ------
    InputError
        Naming the file (and the line): not text, a vertex that is not three finite numbers
        of metres, a face of fewer than three vertices or one that refers to a vertex the
        file does not have, no triangles.
    """
    text = read_input_text(path)
    vertices, faces = [], []
    for number, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts or parts[0] not in ("v", "f"):
            continue
        kind = "vertex" if parts[0] == "v" else "face"
        with reading(path, f"not a Wavefront OBJ mesh, bad {kind} on line {number}"):
            if parts[0] == "v":
                vertices.append(_obj_vertex(parts[1:]))
            else:
                faces += _obj_triangles(parts[1:], len(vertices))
    if len(vertices) < 3 or not faces:
        raise InputError(f"{path}: not a triangle mesh (needs 'v' and 'f' lines)")
    vertices, faces = np.array(vertices, dtype=float), np.array(faces, dtype=int)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InputError(f"{path}: a face refers to a vertex that does not exist (the file "
                         f"has {len(vertices)})")
    return vertices, faces


def _obj_vertex(values: list[str]) -> list[float]:
    """x, y, z of a ``v`` line (metres; a fourth value, w, is ignored)."""
    if len(values) < 3:
        raise ValueError("a vertex needs x, y and z")
    vertex = [float(v) for v in values[:3]]
    if not all(math.isfinite(v) and abs(v) <= MAX_HEIGHT for v in vertex):
        raise ValueError(f"coordinates are metres within +-{MAX_HEIGHT:g}")
    return vertex


def _obj_triangles(values: list[str], defined: int) -> list[list[int]]:
    """The triangles (0-based vertex indices) of an ``f`` line, fanned from its first vertex;
    negative indices count back from the last vertex defined so far."""
    index = [int(v.split("/")[0]) for v in values]
    if len(index) < 3:
        raise ValueError("a face needs at least three vertices")
    index = [i - 1 if i > 0 else defined + i for i in index]
    return [[index[0], index[k], index[k + 1]] for k in range(1, len(index) - 1)]


def mesh_heights(vertices: np.ndarray, faces: np.ndarray, cell: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Rasterise the top of a triangle mesh: heights (nx, ny) (highest hit of a vertical ray
    at each grid point; NaN where none) and the grid origin (3,), both world frame."""
    lo, hi = vertices[:, :2].min(axis=0), vertices[:, :2].max(axis=0)
    nx, ny = (np.floor((hi - lo) / cell).astype(int) + 1)
    x = lo[0] + cell * np.arange(nx)
    y = lo[1] + cell * np.arange(ny)
    heights = np.full((nx, ny), -np.inf)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    for t in range(len(faces)):
        tri = np.stack([a[t], b[t], c[t]])
        tlo, thi = tri[:, :2].min(axis=0), tri[:, :2].max(axis=0)
        i0, i1 = np.searchsorted(x, tlo[0] - 1e-9), np.searchsorted(x, thi[0] + 1e-9, "right")
        j0, j1 = np.searchsorted(y, tlo[1] - 1e-9), np.searchsorted(y, thi[1] + 1e-9, "right")
        if i0 >= i1 or j0 >= j1:
            continue
        px, py = np.meshgrid(x[i0:i1], y[j0:j1], indexing="ij")
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = tri
        det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
        if abs(det) < 1e-15:
            continue  # vertical triangle: no top surface
        l0 = ((y1 - y2) * (px - x2) + (x2 - x1) * (py - y2)) / det
        l1 = ((y2 - y0) * (px - x2) + (x0 - x2) * (py - y2)) / det
        l2 = 1.0 - l0 - l1
        inside = (l0 >= -1e-9) & (l1 >= -1e-9) & (l2 >= -1e-9)
        z = l0 * z0 + l1 * z1 + l2 * z2
        block = heights[i0:i1, j0:j1]
        heights[i0:i1, j0:j1] = np.where(inside, np.maximum(block, z), block)
    heights[~np.isfinite(heights)] = np.nan
    return heights, np.array([lo[0], lo[1], 0.0])


def _number(table: dict, key: str, default: float, source: str) -> float:
    value = table.get(key, default)
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        raise InputError(f"{source}: {key} must be a number, got {value!r}")
    return float(value)


def _pair(table: dict, key: str, source: str):
    value = table.get(key)
    if value is None:
        return None
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       and math.isfinite(v) for v in value)):
        raise InputError(f"{source}: {key} must be [x, y] in metres, got {value!r}")
    return [float(v) for v in value]


def _from_toml(path: Path) -> Surface:
    source = str(path)
    table = read_input_toml(path)
    kind = table.get("type")
    center = _pair(table, "wipe_center", source)
    friction = _number(table, "friction", 0.4, source)
    if not 0.0 < friction <= 2.0:
        raise InputError(f"{source}: friction must be in (0, 2], got {friction}")
    if kind in _BUILDERS:
        known = {"flat": ("height", "tilt_x", "tilt_y"),
                 "bowl": ("height", "radius", "depth"),
                 "sink": ("height", "edge", "edge_width", "edge_y")}[kind]
        unknown = sorted(set(table) - set(known) - {"type", "wipe_center", "friction"})
        if unknown:
            raise InputError(f"{source}: unknown key(s) for type {kind!r}: {', '.join(unknown)}")
        kwargs = {k: _number(table, k, 0.0, source) for k in known if k in table}
        if center is not None:
            kwargs["wipe_center"] = center
        return replace(_BUILDERS[kind](friction=friction, **kwargs), name=path.stem)
    if kind not in ("heightfield", "mesh"):
        raise InputError(f"{source}: type must be one of flat, bowl, sink, heightfield, mesh; "
                         f"got {kind!r}")
    if not isinstance(table.get("file"), str):
        raise InputError(f"{source}: {kind} needs file = \"<path>\"")
    data_path = (path.parent / table["file"]).resolve()
    if not data_path.is_file():
        raise InputError(f"{source}: file {table['file']!r} does not exist")
    if kind == "heightfield":
        heights = read_input_npy(data_path)
        origin = table.get("origin", [0.0, 0.0, 0.0])
        if (not isinstance(origin, list) or len(origin) != 3
                or not all(isinstance(v, (int, float)) for v in origin)):
            raise InputError(f"{source}: origin must be [x, y, z] in metres, got {origin!r}")
        return heightfield_surface(path.stem, heights, table.get("cell", 0.01), origin, center,
                                   friction, str(data_path))
    vertices, faces = read_obj(data_path)
    cell = _number(table, "cell", 0.005, source)
    if cell <= 0:
        raise InputError(f"{source}: cell must be a positive number of metres, got {cell:g}")
    span = vertices[:, :2].max(axis=0) - vertices[:, :2].min(axis=0)
    if np.prod(np.floor(span / cell) + 1) > MAX_GRID_POINTS:
        raise InputError(f"{data_path}: the mesh spans {span[0]:g} m x {span[1]:g} m, more than "
                         f"{MAX_GRID_POINTS:.0e} grid points at a cell of {cell:g} m")
    heights, origin = mesh_heights(vertices, faces, cell)
    if np.isnan(heights).mean() > 0.5:
        raise InputError(f"{data_path}: the mesh has no upward-facing surface over most of its "
                         "footprint")
    footprint = ~np.isnan(heights)
    heights = np.where(footprint, heights, np.nanmin(heights))
    given = center is not None
    if not given:
        center = origin[:2] + (np.array(heights.shape) - 1) * cell / 2
    return Surface(path.stem, "mesh", heights, cell, origin, np.asarray(center, dtype=float),
                   friction, {"file": str(data_path), "cell": cell}, mesh_file=data_path,
                   footprint=footprint, wipe_center_given=given)


def load_surface(spec: str | os.PathLike) -> Surface:
    """A built-in name (``flat``, ``bowl``, ``sink``) or a TOML file -> :class:`Surface`.

    Raises
    ------
    InputError
        Unknown name, unreadable or invalid file (the message names the file and the problem).
    """
    text = str(spec)
    if text in _BUILDERS:
        return _BUILDERS[text]()
    path = Path(text)
    if path.suffix.lower() != ".toml":
        raise InputError(f"--surface: unknown surface {text!r} (expected one of "
                         f"{', '.join(BUILTIN_SURFACES)} or a .toml file)")
    if not path.is_file():
        raise InputError(f"{text}: surface file does not exist")
    return _from_toml(path)
