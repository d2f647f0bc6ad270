"""Procedural surface textures (BGR uint8 images), drawn with numpy and OpenCV.

Each function takes a random generator, the texture's size in metres and its resolution in
pixels per metre; colours are OpenCV HSV triples (hue 0-179, saturation and value 0-255).
"""

from __future__ import annotations

import cv2
import numpy as np


def hsv_to_bgr(hsv) -> tuple[int, int, int]:
    """One OpenCV HSV colour -> BGR ints."""
    pixel = np.uint8([[np.clip(np.round(hsv), 0, [179, 255, 255])]])
    return tuple(int(c) for c in cv2.cvtColor(pixel, cv2.COLOR_HSV2BGR)[0, 0])


def noise_field(rng: np.random.Generator, shape: tuple[int, int], cell_px: float) -> np.ndarray:
    """Smooth noise in about [-1, 1], (h, w) float32, features about ``cell_px`` pixels wide."""
    h, w = shape
    gh, gw = max(2, int(h / cell_px) + 2), max(2, int(w / cell_px) + 2)
    grid = rng.uniform(-1.0, 1.0, (gh, gw)).astype(np.float32)
    big = cv2.resize(grid, (int(gw * cell_px), int(gh * cell_px)), interpolation=cv2.INTER_CUBIC)
    return np.clip(big[:h, :w], -1.2, 1.2)


def fractal_noise(rng, shape, cell_px, octaves=4) -> np.ndarray:
    """Sum of noise fields at halving scales, about [-1, 1]."""
    total = np.zeros(shape, np.float32)
    weight = 1.0
    for _ in range(octaves):
        total += weight * noise_field(rng, shape, max(cell_px, 1.5))
        cell_px /= 2.0
        weight /= 2.0
    return total / 1.9


def _from_hsv_planes(hue, sat, val) -> np.ndarray:
    """Float planes (OpenCV units) -> BGR uint8."""
    hsv = np.dstack([np.clip(hue, 0, 179.9) * 2.0, np.clip(sat, 0, 255) / 255.0,
                     np.clip(val, 0, 255) / 255.0]).astype(np.float32)
    return np.clip(cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR) * 255.0 + 0.5, 0, 255).astype(np.uint8)


def _shape(size_m, px_per_m):
    return int(round(size_m[1] * px_per_m)), int(round(size_m[0] * px_per_m))


def streaks(rng, shape, along_px: float, across_px: float) -> np.ndarray:
    """Noise stretched along x (wood grain, brushed surfaces), about [-1, 1], (h, w)."""
    h, w = shape
    small = noise_field(rng, (max(2, int(h / across_px) + 2), max(2, int(w / along_px) + 2)), 1.0)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)


def wood(rng, size_m, px_per_m, hsv) -> np.ndarray:
    """Planks along the texture's x: per-plank tone, long grain streaks, soft growth rings."""
    h, w = _shape(size_m, px_per_m)
    y = np.mgrid[0:h, 0:w][0].astype(np.float32) / px_per_m
    plank_m = rng.uniform(0.09, 0.2)
    plank = np.floor(y / plank_m)
    tone = np.asarray(rng.uniform(-18, 18, int(plank.max()) + 2), np.float32)[plank.astype(int)]
    grain = (streaks(rng, (h, w), 0.3 * px_per_m, 0.0015 * px_per_m) * rng.uniform(6, 14)
             + streaks(rng, (h, w), 0.08 * px_per_m, 0.004 * px_per_m) * rng.uniform(4, 10))
    warp = streaks(rng, (h, w), 0.4 * px_per_m, 0.03 * px_per_m) * rng.uniform(0.01, 0.03)
    ring_m = rng.uniform(0.008, 0.02)
    rings = np.abs(np.sin(np.pi * (y + warp) / ring_m)) ** 6 * rng.uniform(8, 20)
    val = hsv[2] + tone + grain - rings
    seam = np.abs(y / plank_m - np.round(y / plank_m)) * plank_m < 0.0012
    val = np.where(seam, val * 0.6, val)
    sat = hsv[1] + grain * 0.6 + tone * 0.5 + rings * 0.5
    return _from_hsv_planes(np.full_like(val, hsv[0]) + grain * 0.1, sat, val)


def laminate(rng, size_m, px_per_m, hsv) -> np.ndarray:
    """A plain plastic surface with faint speckle and a soft sheen."""
    h, w = _shape(size_m, px_per_m)
    speckle = noise_field(rng, (h, w), 2.0) * rng.uniform(2, 6)
    sheen = noise_field(rng, (h, w), 0.4 * px_per_m) * rng.uniform(3, 8)
    val = hsv[2] + speckle + sheen
    return _from_hsv_planes(np.full((h, w), hsv[0], np.float32), np.full((h, w), hsv[1]), val)


def marble(rng, size_m, px_per_m, hsv) -> np.ndarray:
    """A pale stone with dark wandering veins."""
    h, w = _shape(size_m, px_per_m)
    y, x = np.mgrid[0:h, 0:w].astype(np.float32) / px_per_m
    turbulence = fractal_noise(rng, (h, w), 0.3 * px_per_m, octaves=5)
    angle = rng.uniform(0, np.pi)
    along = x * np.cos(angle) + y * np.sin(angle)
    veins = np.abs(np.sin(along * rng.uniform(6, 14) + turbulence * rng.uniform(3, 6)))
    vein_dark = np.clip(1.0 - veins / 0.08, 0, 1) * rng.uniform(40, 90)
    cloud = fractal_noise(rng, (h, w), 0.1 * px_per_m) * 10
    val = hsv[2] - vein_dark + cloud
    return _from_hsv_planes(np.full((h, w), hsv[0], np.float32), hsv[1] + cloud * 0.5, val)


def tiles(rng, size_m, px_per_m, hsv) -> np.ndarray:
    """Square glazed tiles with grout lines."""
    h, w = _shape(size_m, px_per_m)
    y, x = np.mgrid[0:h, 0:w].astype(np.float32) / px_per_m
    tile_m = rng.uniform(0.08, 0.25)
    grout_m = rng.uniform(0.002, 0.006)
    ix, iy = np.floor(x / tile_m).astype(int), np.floor(y / tile_m).astype(int)
    tone = rng.uniform(-10, 10, (iy.max() + 2, ix.max() + 2)).astype(np.float32)[iy, ix]
    fx, fy = x / tile_m - ix, y / tile_m - iy
    edge = np.minimum(np.minimum(fx, 1 - fx), np.minimum(fy, 1 - fy)) * tile_m
    grout = edge < grout_m / 2
    val = hsv[2] + tone + noise_field(rng, (h, w), 3.0) * 3
    sat = np.full((h, w), hsv[1], np.float32)
    grout_val = rng.uniform(120, 220)
    val = np.where(grout, grout_val, val)
    sat = np.where(grout, 10, sat)
    return _from_hsv_planes(np.full((h, w), hsv[0], np.float32), sat, val)


def cloth(rng, size_m, px_per_m, hsv, second_hsv=None, check_m=0.03, folds=3) -> np.ndarray:
    """Woven cloth, plain or checkered (``second_hsv``), with soft folds shading it."""
    h, w = _shape(size_m, px_per_m)
    y, x = np.mgrid[0:h, 0:w].astype(np.float32) / px_per_m
    hue = np.full((h, w), hsv[0], np.float32)
    sat = np.full((h, w), hsv[1], np.float32)
    val = np.full((h, w), hsv[2], np.float32)
    if second_hsv is not None:
        stripes_x = (np.floor(x / check_m) % 2).astype(bool)
        stripes_y = (np.floor(y / check_m) % 2).astype(bool)
        both, one = stripes_x & stripes_y, stripes_x ^ stripes_y
        for plane, a, b in ((hue, hsv[0], second_hsv[0]), (sat, hsv[1], second_hsv[1]),
                            (val, hsv[2], second_hsv[2])):
            plane[both] = b
            plane[one] = 0.5 * (a + b) if plane is not hue else (a if hsv[1] > second_hsv[1] else b)
        sat[one] = 0.5 * (hsv[1] + second_hsv[1])
    weave = np.sin(x * px_per_m * 2.1) * np.sin(y * px_per_m * 2.1) * 4
    val = val + weave + noise_field(rng, (h, w), 2.0) * 4
    val = val * fold_shading(rng, (h, w), px_per_m, folds)
    return _from_hsv_planes(hue, sat, val)


def fold_shading(rng, shape, px_per_m, folds: int) -> np.ndarray:
    """Multiplicative shading (h, w) of soft folds: ridges lit on one side, dark on the other."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float32) / px_per_m
    shade = np.ones(shape, np.float32)
    for _ in range(folds):
        angle = rng.uniform(0, np.pi)
        offset = rng.uniform(0, max(w, h) / px_per_m)
        width = rng.uniform(0.01, 0.04)
        d = (x * np.cos(angle) + y * np.sin(angle) - offset * 0.7) / width
        shade *= 1.0 + rng.uniform(0.08, 0.25) * (-d * np.exp(-0.5 * d * d))
    return shade + fractal_noise(rng, shape, 0.1 * px_per_m) * 0.04


def towel(rng, size_m, px_per_m, hsv, folds) -> np.ndarray:
    """Terry cloth: a fine loop texture and folds."""
    h, w = _shape(size_m, px_per_m)
    loops = noise_field(rng, (h, w), 1.5) * 14 + noise_field(rng, (h, w), 4.0) * 8
    val = (hsv[2] + loops) * fold_shading(rng, (h, w), px_per_m, folds)
    hue = np.full((h, w), hsv[0], np.float32)
    return _from_hsv_planes(hue, hsv[1] + loops * 0.5, val)


def painted_wall(rng, size_m, px_per_m, hsv) -> np.ndarray:
    """Matt paint, lighter towards the top."""
    h, w = _shape(size_m, px_per_m)
    gradient = np.linspace(15, -15, h, dtype=np.float32)[:, None]
    val = hsv[2] + gradient + noise_field(rng, (h, w), 0.5 * px_per_m) * 6
    return _from_hsv_planes(np.full((h, w), hsv[0], np.float32), np.full((h, w), hsv[1]), val)


TABLE_TEXTURES = ("wood", "laminate", "marble", "tiles", "cloth", "checkered")


def table_texture(kind: str, rng, size_m, px_per_m, hsv, second_hsv=None) -> np.ndarray:
    """The texture of a table top of ``kind`` (one of :data:`TABLE_TEXTURES`)."""
    if kind == "wood":
        return wood(rng, size_m, px_per_m, hsv)
    if kind == "laminate":
        return laminate(rng, size_m, px_per_m, hsv)
    if kind == "marble":
        return marble(rng, size_m, px_per_m, hsv)
    if kind == "tiles":
        return tiles(rng, size_m, px_per_m, hsv)
    if kind == "cloth":
        return cloth(rng, size_m, px_per_m, hsv, folds=int(rng.integers(1, 4)))
    if kind == "checkered":
        return cloth(rng, size_m, px_per_m, hsv, second_hsv, check_m=rng.uniform(0.012, 0.05),
                     folds=int(rng.integers(1, 4)))
    raise ValueError(f"unknown table texture {kind!r}")


def pores(rng, size_px: int) -> np.ndarray:
    """A tile of sponge pores: multiplicative gain around 1, (size, size) float32."""
    fine = noise_field(rng, (size_px, size_px), 1.2)
    coarse = noise_field(rng, (size_px, size_px), 3.0)
    holes = np.clip((fine + 0.5 * coarse) - 0.7, 0, None) * 0.6
    return (1.0 - holes + 0.04 * fine).astype(np.float32)
