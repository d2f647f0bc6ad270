"""The static part of a synthetic view: table, floor, the demonstrator's body, the wall.

Each camera's background is ray-cast once per demo: every pixel's viewing ray (through the
lens distortion) is intersected with the scene's planes and the nearest hit is looked up in
a procedural texture. The moving parts are drawn over it frame by frame
(:mod:`wipelab.vision.synthetic_renderer`).
"""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.calibration import Camera
from wipelab.vision.projection import pixel_rays
from wipelab.vision.sampling import sample_bilinear
from wipelab.vision.synthetic_rig import SceneLayout

#: Texture resolution of the table top, metres per texel.
TABLE_TEXEL = 0.001
#: Texture resolution of the floor, the body and the wall, metres per texel.
COARSE_TEXEL = 0.004


def fractal_noise(rng: np.random.Generator, shape: tuple[int, int],
                  scales: tuple[int, ...] = (4, 16, 64), weights: tuple[float, ...] = (1, .5, .25)
                  ) -> np.ndarray:
    """Smooth random field in [-1, 1], shape ``shape``: octaves of upsampled white noise.

    ``scales`` are the octaves' cell counts along the longer side.
    """
    height, width = shape
    field = np.zeros(shape, np.float32)
    for cells, weight in zip(scales, weights):
        coarse = rng.standard_normal((max(2, cells * height // max(shape)),
                                      max(2, cells * width // max(shape)))).astype(np.float32)
        field += weight * cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    return field / max(1e-6, float(np.abs(field).max()))


def wood_texture(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Light wooden table top, BGR uint8, grain along the first (x) axis."""
    height, width = shape
    warp = fractal_noise(rng, shape, (4, 16, 64), (1.0, 0.4, 0.2))
    cols = np.arange(width, dtype=np.float32)[None, :]
    grain = np.sin(cols * 0.33 + 7.0 * warp) * 0.5 + 0.5
    grain = grain ** 4
    fine = fractal_noise(rng, shape, (60, 240), (0.5, 0.5))
    planks = (np.floor(cols / 180.0) % 3)  # three shades of plank
    shade = 1.0 - 0.12 * grain - 0.04 * fine - 0.035 * planks
    base = np.array([150, 188, 214], np.float32)  # B, G, R: light oak
    return np.clip(shade[..., None] * base, 0, 255).astype(np.uint8)


def fabric_texture(rng: np.random.Generator, shape: tuple[int, int],
                   bgr: tuple[int, int, int]) -> np.ndarray:
    """Cloth with folds (low-saturation colour ``bgr``), BGR uint8."""
    folds = fractal_noise(rng, shape, (3, 9, 40), (1.0, 0.4, 0.15))
    shade = 0.85 + 0.15 * folds
    return np.clip(shade[..., None] * np.array(bgr, np.float32), 0, 255).astype(np.uint8)


def tile_texture(rng: np.random.Generator, shape: tuple[int, int], tile_texels: int,
                 bgr: tuple[int, int, int]) -> np.ndarray:
    """Floor tiles with grout lines, BGR uint8."""
    height, width = shape
    stains = fractal_noise(rng, shape, (8, 40), (1.0, 0.5))
    rows = np.arange(height)[:, None] % tile_texels
    cols = np.arange(width)[None, :] % tile_texels
    grout = (rows < 2) | (cols < 2)
    shade = np.where(grout, 0.6, 0.95 + 0.05 * stains)
    return np.clip(shade[..., None] * np.array(bgr, np.float32), 0, 255).astype(np.uint8)


class StaticScene:
    """The textured planes of the synthetic kitchen, seeded.

    Parameters
    ----------
    layout : SceneLayout
    seed : int
    """

    def __init__(self, layout: SceneLayout, seed: int):
        self.layout = layout
        rng = np.random.default_rng([seed, 0x5CE7E])
        (x0, x1), (y0, y1) = layout.table_x, layout.table_y
        self.table = wood_texture(rng, (int(round((x1 - x0) / TABLE_TEXEL)),
                                        int(round((y1 - y0) / TABLE_TEXEL))))
        self.floor = tile_texture(rng, (800, 800), 75, (118, 120, 124))
        self.body = fabric_texture(rng, (200, 150), (112, 98, 92))
        self.wall = fabric_texture(rng, (500, 1000), (196, 203, 205))

    def render_background(self, camera: Camera, T_world_cam: np.ndarray) -> np.ndarray:
        """What ``camera`` sees with no sponge or person, BGR uint8 (height, width, 3).

        Parameters
        ----------
        camera : Camera
            Intrinsics and distortion (its ``T_cam_ref`` is not used).
        T_world_cam : ndarray, shape (4, 4)
            The camera's optical frame in the world.
        """
        lay = self.layout
        width, height = lay.image_size
        grid = np.mgrid[0:height, 0:width][::-1].reshape(2, -1).T.astype(np.float64)
        rays = pixel_rays(grid, camera.K, camera.D) @ T_world_cam[:3, :3].T
        origin = T_world_cam[:3, 3]
        best = np.full(len(rays), np.inf)
        image = np.zeros((len(rays), 3), np.uint8)

        def hit(axis: int, value: float) -> tuple[np.ndarray, np.ndarray]:
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (value - origin[axis]) / rays[:, axis]
            s = np.where(np.isfinite(s) & (s > 0), s, np.inf)
            return s, origin + s[:, None] * rays

        def paint(s: np.ndarray, inside: np.ndarray, texture: np.ndarray,
                  u: np.ndarray, v: np.ndarray) -> None:
            use = inside & (s < best)
            if not use.any():
                return
            image[use] = sample_bilinear(texture, np.stack([u[use], v[use]], -1), reflect=True)
            best[use] = s[use]

        (x0, x1), (y0, y1), z_table = lay.table_x, lay.table_y, lay.table_height
        s, p = hit(2, z_table)
        paint(s, (p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1),
              self.table, (p[:, 1] - y0) / TABLE_TEXEL, (p[:, 0] - x0) / TABLE_TEXEL)
        s, p = hit(0, x0)  # the table's front edge, darker
        edge = (p[:, 2] <= z_table) & (p[:, 2] >= z_table - 0.04) & (p[:, 1] >= y0) & (p[:, 1] <= y1)
        paint(s, edge, (self.table // 2 + 20).astype(np.uint8),
              (p[:, 1] - y0) / TABLE_TEXEL, (z_table - p[:, 2]) / TABLE_TEXEL)
        s, p = hit(2, 0.0)
        paint(s, np.ones(len(s), bool), self.floor, p[:, 1] / COARSE_TEXEL, p[:, 0] / COARSE_TEXEL)
        s, p = hit(0, lay.demonstrator_x)
        body = (np.abs(p[:, 1]) <= 0.24) & (p[:, 2] >= z_table - 0.3) & (p[:, 2] <= z_table + 0.8)
        paint(s, body, self.body, (p[:, 1] + 0.3) / COARSE_TEXEL, (z_table + 0.8 - p[:, 2]) / COARSE_TEXEL)
        s, p = hit(0, lay.demonstrator_x + 1.2)
        paint(s, np.ones(len(s), bool), self.wall, (p[:, 1] + 2.0) / COARSE_TEXEL,
              (2.5 - p[:, 2]) / COARSE_TEXEL)
        background = image.reshape(height, width, 3)
        return cv2.GaussianBlur(background, (0, 0), 0.6)  # lens blur
