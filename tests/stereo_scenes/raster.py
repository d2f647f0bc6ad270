"""Drawing 3-D things into (a window of) a camera's canvas with OpenCV.

A :class:`Painter` draws into ``image``, the window of the canvas whose top-left canvas pixel
is ``origin``. Polygons are clipped at a near plane in the camera frame, projected through
the canvas's pinhole model and filled anti-aliased with sub-pixel precision; surfaces are
shaded by a :class:`Light` (Lambert plus ambient).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from tests.stereo_scenes.camera import Canvas
from tests.stereo_scenes.shapes import clip_polygon, perpendicular_axes

SHIFT = 4                 # sub-pixel bits of cv2.fillPoly
NEAR = 0.02               # metres
OUTLINE_ANGLES = np.linspace(0, 2 * np.pi, 16, endpoint=False)


@dataclass
class Light:
    """A directional light plus ambient light.

    ``direction`` (3,) points from the scene towards the light (world, unit); a surface
    of colour c and normal n shows ``c * gain * (ambient + diffuse * max(0, n . direction))``.
    """

    direction: np.ndarray
    ambient: float
    diffuse: float
    gain: float

    def shade(self, colour, normal) -> tuple[float, float, float]:
        """The BGR colour a surface of ``colour`` facing ``normal`` shows."""
        lit = self.ambient + self.diffuse * max(0.0, float(np.dot(normal, self.direction)))
        return tuple(float(min(255.0, c * lit * self.gain)) for c in colour)


class Painter:
    """Draws into ``image`` (BGR uint8), the canvas window starting at ``origin`` (x, y)."""

    def __init__(self, canvas: Canvas, image: np.ndarray, origin=(0, 0), light: Light = None):
        self.canvas, self.image, self.light = canvas, image, light
        self.origin = np.asarray(origin, float)
        self.eye = canvas.camera.centre

    # -- projection ---------------------------------------------------------------------
    def to_pixels(self, points_world: np.ndarray) -> np.ndarray:
        """Window pixel coordinates (..., 2) of world points assumed in front of the camera."""
        uv, _ = self.canvas.project(points_world)
        return uv - self.origin

    def _clipped(self, polygon_world: np.ndarray) -> np.ndarray | None:
        cam = self.canvas.camera.to_camera(polygon_world)
        if np.all(cam[:, 2] >= NEAR):
            return self.to_pixels(polygon_world)
        cam = clip_polygon(cam, np.array([0, 0, 1.0]), NEAR)
        if len(cam) < 3:
            return None
        K = self.canvas.K
        return np.stack([K[0, 0] * cam[:, 0] / cam[:, 2] + K[0, 2],
                         K[1, 1] * cam[:, 1] / cam[:, 2] + K[1, 2]], axis=-1) - self.origin

    def facing(self, point, normal) -> bool:
        """Whether a surface at ``point`` with ``normal`` faces the camera."""
        return float(np.dot(self.eye - point, normal)) > 0.0

    # -- filling -------------------------------------------------------------------------
    def fill_pixels(self, pixels: np.ndarray, colour, target: np.ndarray | None = None):
        """Fills a polygon given in window pixels (k, 2)."""
        pts = np.round(pixels * (1 << SHIFT)).astype(np.int32)
        if np.abs(pts).max() > 2 ** 30:
            return
        cv2.fillPoly(self.image if target is None else target, [pts], colour, cv2.LINE_AA, SHIFT)

    def polygon(self, polygon_world: np.ndarray, colour, target: np.ndarray | None = None):
        """Fills a planar polygon (k, 3) given in the world."""
        pixels = self._clipped(np.asarray(polygon_world, float))
        if pixels is not None:
            self.fill_pixels(pixels, colour, target)

    def solid(self, faces_world, colours):
        """A convex solid: its faces (polygon (k, 3), normal (3,)) facing the camera, shaded."""
        for (poly, normal), colour in zip(faces_world, colours):
            if self.facing(poly.mean(axis=0), normal):
                self.polygon(poly, self.light.shade(colour, normal))

    def silhouette(self, points_world: np.ndarray, target: np.ndarray, value=255):
        """Fills the convex hull of projected points (in front of the camera) into ``target``."""
        pixels = self.to_pixels(points_world)
        hull = cv2.convexHull(pixels.astype(np.float32))[:, 0, :]
        self.fill_pixels(hull, value, target)

    # -- round things --------------------------------------------------------------------
    def _sphere_outline(self, centre, radius, n=16) -> np.ndarray:
        uv, z = self.canvas.project(centre)
        r_px = self.canvas.focal() * radius / max(float(z), NEAR)
        angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
        return uv - self.origin + r_px * np.stack([np.cos(angle), np.sin(angle)], axis=-1)

    def capsule(self, p0, p1, r0, r1, colour, target: np.ndarray | None = None):
        """A tapered capsule (limb, finger) shaded as a cylinder in bands; into ``target``
        as a plain mask of value ``colour`` when given."""
        ends = clip_capsule(self.canvas.camera, p0, p1, r0, r1)
        if ends is None:
            return
        p0, p1, cut0, cut1 = ends
        uv, z = self.canvas.project(np.array([p0, p1]))
        radius_px = self.canvas.focal() * np.array([r0, r1]) / z
        circle = np.stack([np.cos(OUTLINE_ANGLES), np.sin(OUTLINE_ANGLES)], axis=-1)
        # a cut end has no round cap: its sides end at the cut
        pts = [uv[i] + radius_px[i] * (0.1 if cut else 1.0) * circle
               for i, cut in enumerate((cut0, cut1))]
        axis = p1 - p0
        length = np.linalg.norm(axis)
        view = self.eye - 0.5 * (p0 + p1)
        view /= np.linalg.norm(view)
        side = np.cross(axis / length, view) if length > 1e-6 else perpendicular_axes(view)[0]
        if np.linalg.norm(side) < 1e-6:
            side = perpendicular_axes(axis)[0]
        side /= np.linalg.norm(side)
        front = view - np.dot(view, side) * side
        front /= np.linalg.norm(front)
        bands = 1 if target is not None else int(np.clip(radius_px.max() / 2.0, 1, 16))
        edges = np.linspace(-0.97, 0.97, bands + 1)
        corners = np.concatenate([p0 + r0 * edges[:, None] * side, p1 + r1 * edges[:, None] * side])
        corner_px = self.to_pixels(corners)
        rim = np.vstack(pts + [corner_px + self.origin])
        outline = cv2.convexHull((rim - self.origin).astype(np.float32))[:, 0, :]
        if target is not None:
            self.fill_pixels(outline, colour, target)
            return
        self.fill_pixels(outline, self.light.shade(colour, front * 0.6))
        n = bands + 1
        for k in range(bands):
            mid = 0.5 * (edges[k] + edges[k + 1])
            normal = mid * side + np.sqrt(1 - mid * mid) * front
            quad = corner_px[[k, n + k, n + k + 1, k + 1]]
            self.fill_pixels(quad, self.light.shade(colour, normal))

    def sphere(self, centre, radius, colour):
        """A shaded sphere (a round fruit, a head)."""
        centre = np.asarray(centre, float)
        view = self.eye - centre
        view /= np.linalg.norm(view)
        self.fill_pixels(self._sphere_outline(centre, radius, 24), self.light.shade(colour, view * 0.5))
        towards = self.light.direction - view * np.dot(self.light.direction, view)
        shift = towards * radius * 0.35
        self.fill_pixels(self._sphere_outline(centre + shift, radius * 0.7, 24),
                         self.light.shade(colour, view))

    # -- textured planes -----------------------------------------------------------------
    def textured_plane(self, texture: np.ndarray, texture_to_world: np.ndarray,
                       region_world: np.ndarray, shade: float = 1.0):
        """Maps ``texture`` onto a plane and shows it inside ``region_world`` (k, 3).

        ``texture_to_world`` (4, 3) maps homogeneous texture pixels (u, v, 1) to homogeneous
        world points (a plane); ``shade`` multiplies the texture.
        """
        pixels = self._clipped(np.asarray(region_world, float))
        if pixels is None:
            return
        h, w = self.image.shape[:2]
        x0, y0 = np.floor(pixels.min(axis=0)).astype(int)
        x1, y1 = np.ceil(pixels.max(axis=0)).astype(int) + 1
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
        if x1 <= x0 or y1 <= y0:
            return
        T = self.canvas.camera.T_cam_world
        world_to_window = self.canvas.K @ np.hstack([T[:3, :3], T[:3, 3:4]])
        window = np.array([[1, 0, self.origin[0] + x0], [0, 1, self.origin[1] + y0], [0, 0, 1.0]])
        H = np.linalg.inv(window) @ world_to_window @ texture_to_world
        warped = cv2.warpPerspective(texture, H, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                                     borderMode=cv2.BORDER_REFLECT)
        alpha = np.zeros((y1 - y0, x1 - x0), np.uint8)
        self.fill_pixels(pixels - [x0, y0], 255, alpha)
        a = alpha.astype(np.float32)[..., None] * (shade / 255.0)
        region = self.image[y0:y1, x0:x1]
        region[:] = np.clip(region * (1.0 - alpha[..., None] / 255.0) + warped * a, 0, 255)


def clip_capsule(camera, p0, p1, r0, r1):
    """A capsule's end points cut where it crosses the camera's near plane (with room for
    its radius) and whether each was cut, ``(p0, p1, cut0, cut1)``, or None when all of it
    is behind."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    z0, z1 = camera.to_camera(np.array([p0, p1]))[:, 2]
    near0, near1 = NEAR + 1.2 * r0, NEAR + 1.2 * r1
    if z0 < near0 and z1 < near1:
        return None
    if z0 < near0:
        return p0 + (p1 - p0) * (near0 - z0) / (z1 - z0), p1, True, False
    if z1 < near1:
        return p0, p1 + (p0 - p1) * (near1 - z1) / (z0 - z1), False, True
    return p0, p1, False, False


def plane_mapping(origin, axis_u, axis_v, metres_per_pixel: float) -> np.ndarray:
    """``texture_to_world`` (4, 3) of a texture lying on the plane through ``origin``, its
    pixel x along ``axis_u`` and y along ``axis_v``."""
    M = np.zeros((4, 3))
    M[:3, 0] = np.asarray(axis_u, float) * metres_per_pixel
    M[:3, 1] = np.asarray(axis_v, float) * metres_per_pixel
    M[:3, 2] = origin
    M[3, 2] = 1.0
    return M
