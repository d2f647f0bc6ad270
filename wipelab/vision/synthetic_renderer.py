"""Frame-by-frame rendering of a synthetic wiping demonstration seen by a stereo pair.

Over the static background of :mod:`wipelab.vision.synthetic_scene` each frame draws, in
painter's order (valid here because the hand and arms are always above the sponge top):
the sponge (a shaded box), the demonstrator's forearm and hand holding it (their palm and
fingers hide part of its top), and, during occlusion events, the demonstrator's other hand
hovering over it between sponge and cameras (hiding it fully). Every outline is projected
through the lens distortion and drawn anti-aliased with sub-pixel precision. Then: motion
blur (the moving parts are drawn at several instants inside the exposure and averaged), lens
blur, lighting drift (a slowly varying gain per colour channel) and sensor noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.vision.calibration import Camera
from wipelab.vision.projection import invert_transform, project_points, transform_points
from wipelab.vision.sponge_box import FACE_NORMALS, FACES, SpongeBox, visible_faces, yaw_rotation
from wipelab.vision.wiping_motion import WipingMotion

#: Named sponge colours synth can render, BGR of a fully lit face.
SPONGE_BGR = {"yellow": (40, 205, 240), "green": (60, 170, 40), "blue": (200, 110, 30),
              "pink": (170, 110, 240), "orange": (30, 130, 245)}
SKIN_BGR = np.array([122, 152, 208], np.float32)
LIGHT_DIRECTION = np.array([-0.35, 0.25, 1.0]) / np.linalg.norm([-0.35, 0.25, 1.0])
_SUBPIXEL_BITS = 4
_SUPERSAMPLING = 8  # the sponge is drawn 8x8 supersampled: its anti-aliased outline is exact
_RING_POINTS = 14
_SHADED_LIMBS = 4  # forearm and palm get a lit core; fingers are too thin to show it
_BLUR_STEP = 2.5  # pixels the sponge may move between two instants drawn for motion blur


@dataclass(frozen=True)
class RenderParams:
    """Camera effects.

    Attributes
    ----------
    exposure : float
        Shutter time, seconds (motion blur spans it).
    noise_std : float
        Sensor noise, grey levels (of 255).
    lighting_drift : float
        Amplitude of the slow relative change of the illumination.
    max_blur_samples : int
        Most instants drawn inside one exposure.
    """

    exposure: float = 1.0 / 250.0
    noise_std: float = 2.0
    lighting_drift: float = 0.10
    max_blur_samples: int = 5


@dataclass(frozen=True)
class OcclusionEvent:
    """The free hand passes over the sponge: in during [t_in, t_full), hiding it fully until
    t_clear, out by t_out. Seconds."""

    t_in: float
    t_full: float
    t_clear: float
    t_out: float


def schedule_occlusions(duration: float, rng: np.random.Generator) -> list[OcclusionEvent]:
    """One full occlusion per started 25 s (at least one), away from start and end."""
    count = max(1, int(duration // 25.0))
    events = []
    for k in range(count):
        hidden = rng.uniform(0.7, 1.2)
        centre = duration * (k + 0.5) / count + rng.uniform(-0.1, 0.1) * duration / count
        centre = float(np.clip(centre, 1.2 + 0.5 * hidden, duration - 0.9 - 0.5 * hidden))
        t_full, t_clear = centre - 0.5 * hidden, centre + 0.5 * hidden
        events.append(OcclusionEvent(t_full - 0.35, t_full, t_clear, t_clear + 0.35))
    return events


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


@dataclass(frozen=True)
class Limbs:
    """Tapered capsules drawn in skin colour: segments ``ends[i, 0]``-``ends[i, 1]`` with
    radii ``radii[i]``.

    Attributes
    ----------
    ends : ndarray, shape (m, 2, 3)
        Segment end points, world frame, metres.
    radii : ndarray, shape (m, 2)
        Radius at each end, metres.
    """

    ends: np.ndarray
    radii: np.ndarray

    @staticmethod
    def empty() -> "Limbs":
        return Limbs(np.zeros((0, 2, 3)), np.zeros((0, 2)))

    @staticmethod
    def concat(parts: list["Limbs"]) -> "Limbs":
        return Limbs(np.concatenate([p.ends for p in parts]),
                     np.concatenate([p.radii for p in parts]))


class WipingScene:
    """Everything that moves, as a function of time, in the world frame.

    Parameters
    ----------
    motion : WipingMotion
        The sponge's pose over time.
    sponge : SpongeBox
    occlusions : list of OcclusionEvent
    eye : ndarray, shape (3,)
        Midpoint between the cameras (the free hand hovers on the line from it to the sponge).
    """

    def __init__(self, motion: WipingMotion, sponge: SpongeBox, occlusions: list[OcclusionEvent],
                 eye: np.ndarray):
        self.motion = motion
        self.sponge = sponge
        self.occlusions = occlusions
        self.eye = np.asarray(eye, float)
        centre_xy = motion.params.centre_xy
        self._elbow_rest = np.array([centre_xy[0] + 0.30, centre_xy[1] - 0.06,
                                     motion.centre_z + 0.20])
        self._centre = np.array([centre_xy[0], centre_xy[1], motion.centre_z])
        self._poses: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def sponge_pose(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Centre (3,) and rotation (3, 3) of the sponge in the world at time t."""
        if t not in self._poses:
            if len(self._poses) > 256:  # both cameras ask for the same instants, then move on
                self._poses.clear()
            centre, yaw = self.motion.pose(np.array([t]))
            self._poses[t] = centre[0], yaw_rotation(yaw[0])
        return self._poses[t]

    def holding_hand(self, centre: np.ndarray, R: np.ndarray) -> Limbs:
        """Forearm, palm, fingers and thumb of the hand holding the sponge (world frame).

        Defined in the sponge frame: the sponge's long side along x, the demonstrator (beyond
        the table) towards its -y side; the palm rests on the rear half of the top, the
        fingers reach towards the front edge.
        """
        ends = centre + (_HAND_ENDS + [0.0, 0.0, 0.5 * self.sponge.height]) @ R.T
        wrist = centre + R @ np.array([0.0, -0.068, 0.5 * self.sponge.height + 0.032])
        elbow = self._elbow_rest + 0.55 * (centre - self._centre) * np.array([1, 1, 0])
        forearm = Limbs(np.stack([elbow, wrist])[None], np.array([[0.040, 0.029]]))
        return Limbs.concat([forearm, Limbs(ends, _HAND_RADII)])

    def occluding_hand(self, t: float, centre: np.ndarray) -> Limbs:
        """The free hand and forearm during an occlusion event (no limbs outside one)."""
        for event in self.occlusions:
            if event.t_in <= t <= event.t_out:
                s = (_smoothstep((t - event.t_in) / (event.t_full - event.t_in))
                     * (1.0 - _smoothstep((t - event.t_clear) / (event.t_out - event.t_clear))))
                break
        else:
            return Limbs.empty()
        hover = centre + 0.26 * (self.eye - centre)
        away = centre + np.array([0.0, 0.42, 0.22])
        return Limbs(away + s * (hover - away) + _FREE_HAND_ENDS, _FREE_HAND_RADII)


def _hand_model() -> tuple[np.ndarray, np.ndarray]:
    """Holding hand in the sponge frame, z from the sponge top: palm (3), fingers (4), thumb."""
    parts = [((-0.022, -0.050, 0.022), (-0.018, 0.000, 0.017), 0.017, 0.016),
             ((0.022, -0.050, 0.022), (0.018, 0.000, 0.017), 0.017, 0.016),
             ((0.000, -0.055, 0.026), (0.000, -0.005, 0.020), 0.018, 0.017)]
    parts += [((x, -0.002, 0.014), (x * 1.1, 0.016, 0.009), 0.0085, 0.0075)
              for x in (-0.027, -0.009, 0.009, 0.027)]
    parts.append(((0.040, -0.035, 0.016), (0.060, -0.008, -0.004), 0.010, 0.009))
    return (np.array([[a, b] for a, b, _, _ in parts]),
            np.array([[ra, rb] for _, _, ra, rb in parts]))


def _free_hand_model() -> tuple[np.ndarray, np.ndarray]:
    """The free hand, flat, palm down, reaching in along world -y, relative to its centre:
    forearm, palm (3), fingers (4)."""
    parts = [((0.0, 0.30, 0.10), (0.0, 0.07, 0.005), 0.042, 0.032)]
    parts += [((x, 0.06, 0.0), (x, -0.04, -0.004), 0.024, 0.022) for x in (-0.028, 0.0, 0.028)]
    parts += [((x, -0.04, -0.004), (x * 1.1, -0.11, -0.01), 0.011, 0.009)
              for x in (-0.033, -0.011, 0.011, 0.033)]
    return (np.array([[a, b] for a, b, _, _ in parts]),
            np.array([[ra, rb] for _, _, ra, rb in parts]))


_HAND_ENDS, _HAND_RADII = _hand_model()
_FREE_HAND_ENDS, _FREE_HAND_RADII = _free_hand_model()
_RING = np.stack([np.cos(np.linspace(0, 2 * np.pi, _RING_POINTS, endpoint=False)),
                  np.sin(np.linspace(0, 2 * np.pi, _RING_POINTS, endpoint=False))], -1)


def limb_outlines(limbs: Limbs, T_cam_world: np.ndarray) -> np.ndarray:
    """Points whose projections' convex hull is each capsule's silhouette, camera frame.

    For each end sphere, a ring of radius r perpendicular to the line of sight.

    Returns
    -------
    ndarray, shape (m, 2 * _RING_POINTS, 3)
    """
    ends = transform_points(T_cam_world, limbs.ends)  # (m, 2, 3)
    view = ends / np.linalg.norm(ends, axis=-1, keepdims=True)
    u = np.cross(view, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    w = np.cross(view, u)
    ring = (_RING[None, None, :, 0, None] * u[:, :, None, :]
            + _RING[None, None, :, 1, None] * w[:, :, None, :])  # (m, 2, ring, 3)
    points = ends[:, :, None, :] + limbs.radii[:, :, None, None] * ring
    return points.reshape(len(ends), -1, 3)


def _face_outlines(sponge: SpongeBox, per_edge: int = 6) -> np.ndarray:
    """Each face's outline subdivided so that distortion can bend it, sponge frame,
    shape (6, 4 * per_edge, 3)."""
    corners = sponge.corners()[FACES]  # (6, 4, 3)
    s = np.linspace(0.0, 1.0, per_edge, endpoint=False)[None, None, :, None]
    a, b = corners[:, :, None, :], np.roll(corners, -1, axis=1)[:, :, None, :]
    return (a + s * (b - a)).reshape(6, -1, 3)


def _offset_inwards(polygon: np.ndarray, distance: float) -> np.ndarray:
    """Move every edge of a convex polygon (m, 2) inwards by ``distance`` (its units).

    ``cv2.fillPoly`` fills pixels whose centres lie on the boundary too, which grows a shape
    by half a pixel; shrinking it by half a (supersampled) pixel first cancels that.
    """
    edges = np.roll(polygon, -1, axis=0) - polygon
    lengths = np.linalg.norm(edges, axis=1, keepdims=True)
    keep = lengths[:, 0] > 1e-9
    polygon, edges, lengths = polygon[keep], edges[keep], lengths[keep]
    area2 = np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
    normals = np.column_stack([-edges[:, 1], edges[:, 0]]) / lengths * np.sign(area2)  # inward
    before = np.roll(normals, 1, axis=0)  # normal of the edge ending at each vertex
    bisector = (before + normals) / np.maximum(1.0 + np.sum(before * normals, axis=1), 0.2)[:, None]
    return polygon + distance * bisector


class StereoRenderer:
    """Draws one camera's frames of a :class:`WipingScene`.

    Parameters
    ----------
    camera : Camera
    T_world_cam : ndarray, shape (4, 4)
        The camera's pose in the world.
    background : ndarray, shape (h, w, 3)
        Static scene seen by this camera, BGR uint8.
    scene : WipingScene
    sponge_bgr : tuple of int
    params : RenderParams
    """

    def __init__(self, camera: Camera, T_world_cam: np.ndarray, background: np.ndarray,
                 scene: WipingScene, sponge_bgr: tuple[int, int, int], params: RenderParams):
        self.camera = camera
        self.T_cam_world = invert_transform(T_world_cam)
        self.eye_world = T_world_cam[:3, 3]
        self.background = background
        self.scene = scene
        self.sponge_bgr = np.array(sponge_bgr, np.float32)
        self._outlines = _face_outlines(scene.sponge)
        self.params = params

    def _project(self, points_world: np.ndarray) -> np.ndarray:
        return project_points(transform_points(self.T_cam_world, points_world), self.camera.K,
                              self.camera.D)

    def _primitives(self, t: float) -> tuple[list[tuple[np.ndarray, np.ndarray]], list, list]:
        """Polygons (pixels) with colours, in drawing order, split into sponge, hand, occluder."""
        scene = self.scene
        centre, R = scene.sponge_pose(t)
        normals = FACE_NORMALS @ R.T
        outlines = centre + self._outlines @ R.T  # (6, k, 3)
        shown = np.flatnonzero(visible_faces(outlines.mean(axis=1), normals, self.eye_world))
        pixels = self._project(outlines[shown])
        shades = 0.38 + 0.62 * np.clip(normals[shown] @ LIGHT_DIRECTION, 0.0, None)
        sponge = [(pixels[i], self.sponge_bgr * shades[i]) for i in range(len(shown))]
        hand = scene.holding_hand(centre, R)
        occluder = scene.occluding_hand(t, centre)
        limbs = self._limb_polygons(Limbs.concat([hand, occluder]))
        return sponge, limbs[:len(hand.ends)], limbs[len(hand.ends):]

    def _key_points(self, t: float) -> np.ndarray:
        """Sponge corners and hand limb ends at time t, world frame (n, 3): what motion blur
        moves (the free hand follows the sponge)."""
        centre, R = self.scene.sponge_pose(t)
        limbs = self.scene.holding_hand(centre, R)
        return np.concatenate([centre + self.scene.sponge.corners() @ R.T,
                               limbs.ends.reshape(-1, 3)])

    def _limb_polygons(self, limbs: Limbs) -> list[tuple[np.ndarray, np.ndarray]]:
        if len(limbs.ends) == 0:
            return []
        pixels = project_points(limb_outlines(limbs, self.T_cam_world), self.camera.K,
                                self.camera.D).astype(np.float32)
        return [(cv2.convexHull(outline).reshape(-1, 2), SKIN_BGR) for outline in pixels]

    @staticmethod
    def _fill(image: np.ndarray, polygon: np.ndarray, colour, offset: np.ndarray,
              antialias: bool = True) -> None:
        fixed = np.round((polygon - offset) * (1 << _SUBPIXEL_BITS)).astype(np.int32)
        cv2.fillPoly(image, [fixed], tuple(float(c) for c in colour),
                     cv2.LINE_AA if antialias else cv2.LINE_8, _SUBPIXEL_BITS)

    @staticmethod
    def _fill_exact(image: np.ndarray, polygons: list[tuple[np.ndarray, np.ndarray]],
                    offset: np.ndarray) -> None:
        """Draw polygons with exact anti-aliasing: supersampled, then area-averaged.

        (``cv2.fillPoly`` rounds vertices to whole pixels and includes boundary pixels, which
        would make the sponge look up to a pixel larger than it is.)
        """
        if not polygons:
            return
        S = _SUPERSAMPLING
        every = np.concatenate([polygon for polygon, _ in polygons]) - offset
        x0, y0 = np.floor(every.min(axis=0)).astype(int) - 1
        x1, y1 = np.ceil(every.max(axis=0)).astype(int) + 2
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, image.shape[1]), min(y1, image.shape[0])
        if x1 <= x0 or y1 <= y0:
            return
        colour = np.zeros(((y1 - y0) * S, (x1 - x0) * S, 3), np.uint8)
        coverage = np.zeros(colour.shape[:2], np.uint8)
        for polygon, bgr in polygons:
            # hi-res pixel j is centred on low-res coordinate x0 - 0.5 + (j + 0.5) / S
            hires = _offset_inwards((polygon - offset - [x0, y0] + 0.5) * S - 0.5, 0.5)
            fixed = [np.round(hires * (1 << _SUBPIXEL_BITS)).astype(np.int32)]
            cv2.fillPoly(colour, fixed, tuple(float(c) for c in bgr), cv2.LINE_8,
                         _SUBPIXEL_BITS)
            cv2.fillPoly(coverage, fixed, 255, cv2.LINE_8, _SUBPIXEL_BITS)
        size = (x1 - x0, y1 - y0)
        premultiplied = cv2.resize(colour, size, interpolation=cv2.INTER_AREA).astype(np.float32)
        alpha = cv2.resize(coverage, size, interpolation=cv2.INTER_AREA).astype(np.float32) / 255
        window = image[y0:y1, x0:x1]
        window[:] = window * (1.0 - alpha[..., None]) + premultiplied

    def _draw(self, image: np.ndarray, primitives, offset: np.ndarray) -> None:
        sponge, hand, occluder = primitives
        self._fill_exact(image, sponge, offset)
        for group in (hand, occluder):
            for polygon, colour in group:  # darker rim, lighter core: a cylinder's shading
                self._fill(image, polygon, colour * 0.78, offset)
            for polygon, colour in group[:_SHADED_LIMBS]:
                core = polygon.mean(axis=0) + 0.6 * (polygon - polygon.mean(axis=0))
                self._fill(image, core, colour, offset)

    def render(self, t: float) -> tuple[np.ndarray, float]:
        """The frame at time t (mid-exposure) before lighting and noise.

        Returns
        -------
        image : ndarray, shape (h, w, 3)
            BGR uint8.
        visible : float
            Fraction of the sponge's pixels not hidden by the free hand (the holding hand is
            part of the normal view), at mid-exposure; 1 when nothing passes over it.
        """
        p = self.params
        height, width = self.background.shape[:2]
        mid = self._primitives(t)
        travel = float(np.max(np.abs(self._project(self._key_points(t + 0.5 * p.exposure))
                                     - self._project(self._key_points(t - 0.5 * p.exposure)))))
        samples = int(np.clip(np.ceil(travel / _BLUR_STEP), 1, p.max_blur_samples))
        instants = (np.linspace(-0.5, 0.5, samples) * p.exposure + t) if samples > 1 else [t]
        drawn = [mid] if samples == 1 else [self._primitives(s) for s in instants]
        every = np.concatenate([poly for prims in drawn for group in prims for poly, _ in group])
        x0, y0 = np.floor(np.nanmin(every, axis=0)).astype(int) - 4
        x1, y1 = np.ceil(np.nanmax(every, axis=0)).astype(int) + 5
        x0, y0 = max(0, x0), max(0, y0)
        x1, y1 = min(width, x1), min(height, y1)
        image = self.background.copy()
        if x1 > x0 and y1 > y0:
            offset = np.array([x0, y0], float)
            window = self.background[y0:y1, x0:x1]
            total = np.zeros(window.shape, np.float32)
            for prims in drawn:
                layer = window.astype(np.float32)
                self._draw(layer, prims, offset)
                total += layer
            # lens blur of what was drawn (the background already has it)
            change = cv2.GaussianBlur(total / len(drawn) - window, (0, 0), 0.6)
            image[y0:y1, x0:x1] = np.clip(window + change + 0.5, 0, 255).astype(np.uint8)
        return image, self._visible_fraction(mid)

    def _visible_fraction(self, primitives) -> float:
        sponge, hand, occluder = primitives
        if not occluder:
            return 1.0
        polygons = [poly for poly, _ in sponge]
        every = np.concatenate(polygons)
        x0, y0 = np.floor(np.nanmin(every, axis=0)).astype(int) - 1
        x1, y1 = np.ceil(np.nanmax(every, axis=0)).astype(int) + 2
        offset = np.array([x0, y0], float)
        mask = np.zeros((max(1, y1 - y0), max(1, x1 - x0)), np.uint8)
        for polygon in polygons:
            self._fill(mask, polygon, (1,), offset, antialias=False)
        for polygon, _ in hand:
            self._fill(mask, polygon, (0,), offset, antialias=False)
        unhidden = int(mask.sum())
        for polygon, _ in occluder:
            self._fill(mask, polygon, (0,), offset, antialias=False)
        return float(mask.sum()) / unhidden if unhidden else 0.0


class CameraEffects:
    """Lighting drift and sensor noise applied to whole frames (seeded, per camera)."""

    def __init__(self, params: RenderParams, image_shape: tuple[int, int, int], seed: int,
                 bank_size: int = 8):
        rng = np.random.default_rng([seed, 0xEFFEC7])
        self.params = params
        self._periods = rng.uniform([15.0, 5.0], [30.0, 9.0])
        self._phases = rng.uniform(0.0, 2 * np.pi, 2)
        self._tint = rng.uniform(-0.25, 0.25, 3)
        bank = rng.normal(0.0, params.noise_std, (bank_size,) + image_shape)
        self._noise_up = np.clip(bank, 0, 255).astype(np.uint8)
        self._noise_down = np.clip(-bank, 0, 255).astype(np.uint8)
        self._rng = rng

    def gain(self, t: float) -> np.ndarray:
        """Per-channel (B, G, R) illumination gain at time t, shape (3,)."""
        waves = np.sin(2 * np.pi * t / self._periods + self._phases)
        drift = self.params.lighting_drift * (0.7 * waves[0] + 0.3 * waves[1])
        return 1.0 + drift * (1.0 + self._tint)  # brighter light is also a little warmer/cooler

    def apply(self, image: np.ndarray, t: float) -> np.ndarray:
        """Lit and noisy copy of a BGR uint8 frame."""
        lit = cv2.multiply(image, tuple(float(g) for g in self.gain(t)) + (1.0,))
        up, down = self._rng.integers(0, len(self._noise_up), 2)
        return cv2.subtract(cv2.add(lit, self._noise_up[up]), self._noise_down[down])
