"""Random surfaces and demonstrations for the adapt benchmark, written as users would bring them.

Shares no code with ``wipelab.sim.surfaces``: surfaces are written to disk as the TOML files of
DESIGN.md ("Surfaces") with a ``.npy`` heightfield or an ``.obj`` mesh, and the stage reads them
as it reads a user's. What users have (issue 10): table tops 0.6-1.0 m high, slopes up to 10
degrees, bumps and dips, curved counters, a basin with a raised rim, anywhere in front of the
robot (which stands at the origin facing +x); demonstrations 10-40 cm across at a human tempo.

- :func:`heightfield` a table top: a plane tilted up to 10 deg in a random direction plus a few
  Gaussian bumps and dips (0.5-2 cm), 0.6-1.2 m by 0.5-1.2 m, its near edge 0.4-1.3 m ahead.
- :func:`mesh` a counter as an OBJ triangle mesh: either a top bent about a horizontal axis
  (radius 0.6-2 m, up or down) or a flat top with a sunk basin and a rounded rim; its footprint
  is a rectangle or a rectangle with a rounded front (a quarter of it cut on a circle).
- :func:`demonstration` a periodic wiping path (circle, ellipse, figure-8, zig-zag stroke)
  10-40 cm across, as a 30 Hz tracked trajectory with 2 mm noise, at an average hand speed of
  0.25-0.5 m/s (0.4-1.5 Hz), somewhere in a camera's world frame.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

#: Seeds the benchmark's defaults were chosen on, and seeds kept for reporting only.
TUNING_SEEDS = (0, 1, 2, 3)
HELD_OUT_SEEDS = (100, 101, 102, 103)


def _bumps(rng: np.random.Generator, gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """A few Gaussian bumps and dips (m) over the grid (gx, gy)."""
    relief = np.zeros_like(gx)
    for _ in range(rng.integers(1, 5)):
        cx, cy = rng.uniform(gx.min(), gx.max()), rng.uniform(gy.min(), gy.max())
        width = rng.uniform(0.05, 0.15)
        relief += rng.choice([-1, 1]) * rng.uniform(0.005, 0.02) * np.exp(
            -((gx - cx) ** 2 + (gy - cy) ** 2) / (2 * width ** 2))
    return relief


def heightfield(rng: np.random.Generator, directory: Path, name: str) -> Path:
    """Write ``name.toml`` + ``name.npy`` (a table top, see the module docstring); returns the
    TOML path."""
    cell = 0.01
    size = np.array([rng.uniform(0.6, 1.2), rng.uniform(0.5, 1.2)])
    shape = np.round(size / cell).astype(int) + 1
    gx, gy = np.meshgrid(*(np.arange(n) * cell for n in shape), indexing="ij")
    slope, direction = math.radians(rng.uniform(0.0, 10.0)), rng.uniform(0.0, 2 * math.pi)
    tilt = math.tan(slope) * ((gx - gx.mean()) * math.cos(direction)
                              + (gy - gy.mean()) * math.sin(direction))
    heights = tilt + _bumps(rng, gx, gy)
    height = rng.uniform(0.6, 1.0)
    origin = [rng.uniform(0.4, 1.3), rng.uniform(-0.9, 0.3) - size[1] / 2, height]
    np.save(directory / f"{name}.npy", heights)
    (directory / f"{name}.toml").write_text(
        f'# random table top: {math.degrees(slope):.1f} deg slope, {height:.2f} m high\n'
        f'type = "heightfield"\nfile = "{name}.npy"\ncell = {cell}\n'
        f'origin = [{origin[0]:.4f}, {origin[1]:.4f}, {origin[2]:.4f}]\n')
    return directory / f"{name}.toml"


def _write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    lines = [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def mesh(rng: np.random.Generator, directory: Path, name: str, bent: bool, rounded: bool
         ) -> Path:
    """Write ``name.toml`` + ``name.obj`` (a counter, see the module docstring: ``bent`` top
    or a basin; a ``rounded`` front or not); returns the TOML path."""
    step = 0.02
    size = np.array([rng.uniform(0.6, 1.0), rng.uniform(0.6, 1.2)])
    nx, ny = (np.round(size / step).astype(int) + 1)
    gx, gy = np.meshgrid(np.arange(nx) * step, np.arange(ny) * step, indexing="ij")
    height = rng.uniform(0.6, 1.0)
    if bent:                     # a top bent about a horizontal axis
        radius, angle = rng.uniform(0.6, 2.0) * rng.choice([-1, 1]), rng.uniform(0, math.pi)
        across = (gx - gx.mean()) * math.cos(angle) + (gy - gy.mean()) * math.sin(angle)
        z = np.sign(radius) * (np.sqrt(radius ** 2 - np.minimum(across ** 2, 0.9 * radius ** 2))
                               - abs(radius))
        kind = f"bent top, radius {radius:+.2f} m"
    else:                        # a sunk basin with a rounded rim
        cx, cy = rng.uniform(0.3, 0.7) * size[0], rng.uniform(0.3, 0.7) * size[1]
        radius, depth = rng.uniform(0.15, 0.3), rng.uniform(0.03, 0.07)
        r = np.hypot(gx - cx, gy - cy) / radius
        z = -depth * np.clip(1.0 - r ** 2, 0.0, None) ** 1.5
        kind = f"basin {2 * radius:.2f} m wide, {depth * 1000:.0f} mm deep"
    origin = np.array([rng.uniform(0.4, 1.2), rng.uniform(-0.9, 0.3) - size[1] / 2])
    keep = np.ones((nx, ny), dtype=bool)
    if rounded:                  # a rounded front: the near corners cut on circles
        bend = rng.uniform(0.2, 0.4) * size.min()
        for cy in (bend, size[1] - bend):
            corner = (gx < bend) & ((gy < bend) if cy == bend else (gy > size[1] - bend))
            keep &= ~(corner & (np.hypot(gx - bend, gy - cy) > bend))
        kind += ", rounded front"
    vertices = np.column_stack([gx.ravel() + origin[0], gy.ravel() + origin[1],
                                z.ravel() + height])
    index = np.arange(nx * ny).reshape(nx, ny)
    faces = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            if keep[i:i + 2, j:j + 2].all():
                a, b, c, d = index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]
                faces += [(a, b, c), (a, c, d)]
    _write_obj(directory / f"{name}.obj", vertices, np.array(faces))
    (directory / f"{name}.toml").write_text(
        f'# random counter: {kind}, {height:.2f} m high\n'
        f'type = "mesh"\nfile = "{name}.obj"\ncell = 0.01\n')
    return directory / f"{name}.toml"


def random_surface(seed: int, directory: Path) -> Path:
    """A heightfield for even seeds, a mesh for odd ones (bent for seed % 4 == 1, a basin for
    seed % 4 == 3; the front rounded every other one); returns its TOML path."""
    rng = np.random.default_rng(seed)
    name = f"random{seed}"
    if seed % 2 == 0:
        return heightfield(rng, directory, name)
    return mesh(rng, directory, name, bent=seed % 4 == 1, rounded=(seed // 4) % 2 == 0)


def demonstration(seed: int) -> tuple[np.ndarray, np.ndarray, str]:
    """A tracked wiping demonstration: time (n,) (s), x-y (n, 2) (m) and a description."""
    rng = np.random.default_rng(10_000 + seed)
    pattern = ("circle", "ellipse", "figure8", "zigzag")[seed % 4]
    across = rng.uniform(0.10, 0.40)
    a, b = across / 2, across / 2 * rng.uniform(0.5, 1.0)
    perimeter = {"circle": 2 * math.pi * a, "ellipse": math.pi * (a + b) * 1.1,
                 "figure8": 6.1 * max(a, b), "zigzag": 4 * a}[pattern]
    frequency = float(np.clip(rng.uniform(0.25, 0.5) / perimeter, 0.4, 1.5))
    t = np.arange(0.0, max(20.0, 12.0 / frequency), 1 / 30)
    phase = 2 * math.pi * frequency * t
    if pattern == "circle":
        xy = np.column_stack([a * np.cos(phase), a * np.sin(phase)])
    elif pattern == "ellipse":
        xy = np.column_stack([a * np.cos(phase), b * np.sin(phase)])
    elif pattern == "figure8":
        xy = np.column_stack([a * np.sin(phase), b * np.sin(2 * phase)])
    else:                        # a stroke back and forth, a little sideways on the way back
        xy = np.column_stack([a * np.sin(phase), 0.25 * b * np.sin(phase) ** 2])
    turn = rng.uniform(0, 2 * math.pi)
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    xy = xy @ rotation.T + rng.uniform(-1, 1, 2)
    xy += rng.normal(scale=0.002, size=xy.shape)
    size = np.ptp(xy, axis=0) * 100
    return t, xy, f"{pattern} {size[0]:.0f} x {size[1]:.0f} cm at {frequency:.2f} Hz"
