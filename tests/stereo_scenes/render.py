"""Frames of a scene: the static background once per camera, the moving things per frame.

Per camera, the static scene is painted once into the canvas (undistorted, supersampled),
blurred by the lens blur and resampled through the lens model into the background image.
Per frame, only the window the moving things (and their shadows) cover is redrawn: the
window of the static canvas is copied, the sponge, hands and arms are painted at several
instants within the exposure and averaged (motion blur), blurred, resampled through the
same maps and pasted into a copy of the background.

The visible fraction of the sponge in a camera is the share of its silhouette (the convex
hull of the box) not covered by the occluding free arm, at the frame's instant; the hand
that holds the sponge does not count.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from tests.stereo_scenes import textures
from tests.stereo_scenes.actors import HoldingHand, SpongeModel, free_arm, grip, holding_hand
from tests.stereo_scenes.camera import Canvas
from tests.stereo_scenes.lens import distort
from tests.stereo_scenes.motion import WipingMotion
from tests.stereo_scenes.raster import NEAR, Light, Painter, clip_capsule
from tests.stereo_scenes.static_scene import StaticTextures, draw_static

MAX_SUBFRAMES = 8
SUBFRAME_STEP_PX = 2.0
SHADOW_SOFTNESS_M = 0.04    # room around shadows for their blur      # motion between averaged instants, output pixels


@dataclass
class MovingState:
    """The moving things at one instant."""

    t: float
    centre: np.ndarray          # sponge box centre, world
    R: np.ndarray               # sponge orientation
    yaw: float
    faces: list
    vertices: np.ndarray
    hand: HoldingHand
    occluder: list              # limbs of the free arm (empty when it is away)


class Scene:
    """The moving parts of a planned scene, shared by both cameras."""

    def __init__(self, plan):
        self.plan = plan
        m = plan.motion
        self.sponge = SpongeModel(plan.sponge)
        self.motion = WipingMotion(m.pattern, m.frequency_hz, m.across, m.aspect, m.centre_xy,
                                   m.orientation, plan.table.height, self.sponge.half, m.yaw0,
                                   m.still_s, plan.duration,
                                   np.random.default_rng([plan.seed, 100]))
        centres, Rs, _ = self.motion.pose(np.linspace(0.0, plan.duration, 61))
        self.grip = grip(plan.person, zip(centres, Rs), plan.table.height)
        left, right = plan.cameras.pair()
        self.eye_mid = 0.5 * (left.centre + right.centre)
        self.camera_right = left.T_world_cam[:3, 0]

    def state(self, t: float) -> MovingState:
        centre, R, yaw = self.motion.pose(np.array([t]))
        centre, R = centre[0], R[0]
        occluder = []
        for event in self.plan.occlusions:
            occluder += free_arm(event, t, centre, self.eye_mid, self.camera_right,
                                 self.plan.person)
        return MovingState(t, centre, R, float(yaw[0]), self.sponge.world_faces(centre, R),
                           self.sponge.world_vertices(centre, R),
                           holding_hand(self.plan.person, self.sponge, centre, R,
                                        self.plan.table.height, self.grip), occluder)


class CameraView:
    """One camera's renderer: its canvas, the static background, the per-frame window."""

    def __init__(self, camera, plan, light: Light, tex: StaticTextures, pores: np.ndarray,
                 scale: float):
        self.camera, self.plan, self.light, self.pores = camera, plan, light, pores
        self.canvas = Canvas(camera, scale)
        w, h = self.canvas.size
        self.static = np.zeros((h, w, 3), np.uint8)
        draw_static(Painter(self.canvas, self.static, (0, 0), light), plan, tex)
        self.sigma = max(0.45, plan.effects.lens_blur_px)
        self.background = self._resample(self.static, 0, 0, camera.height, camera.width)
        self.table_z = plan.table.height

    def _resample(self, canvas_image, y0, x0, y1, x1, origin=(0, 0)):
        """Output pixels [y0:y1, x0:x1] through the lens, blurred by the lens blur."""
        mx = self.canvas.map_x[y0:y1, x0:x1] - np.float32(origin[0])
        my = self.canvas.map_y[y0:y1, x0:x1] - np.float32(origin[1])
        image = cv2.remap(canvas_image, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        return cv2.GaussianBlur(image, (0, 0), self.sigma)

    # -- the window of moving things ------------------------------------------------------
    def _bounding_points(self, state: MovingState) -> np.ndarray:
        """Points (n, 3) whose image bounds everything that moves, shadows included."""
        palm = state.hand.palm.surface_points()
        pts = [state.vertices, palm]
        shadows = [self._on_table(state.vertices), self._on_table(palm)]
        limbs = state.hand.arm + state.hand.hand + [f for f, _, _ in state.hand.fingers]
        axes = self.camera.T_world_cam[:3, :2].T
        for group, shadow in ((limbs, True), (state.occluder, False)):
            for limb in group:
                ends = clip_capsule(self.camera, limb.p0, limb.p1, limb.r0, limb.r1)
                if ends is None:
                    continue
                for p, r in zip(ends[:2], (limb.r0, limb.r1)):
                    ring = p + r * 1.3 * np.vstack([axes, -axes])
                    pts.append(ring)
                    if shadow:
                        shadows.append(self._on_table(ring))
        shadows = np.vstack(shadows)
        soft = SHADOW_SOFTNESS_M * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])
        pts.append((shadows[:, None, :] + soft).reshape(-1, 3))
        return np.vstack(pts)

    def _on_table(self, points):
        L = self.light.direction
        lift = np.maximum(points[:, 2] - self.table_z, 0.0)
        return points - np.outer(lift / L[2], L)

    def _window(self, states):
        """(output window, pasted part of it, canvas window) covering the moving things, as
        (y0, x0, y1, x1) boxes, or None when they are out of view."""
        pts = np.vstack([self._bounding_points(s) for s in states])
        cam_pts = self.camera.to_camera(pts)
        w, h = self.camera.width, self.camera.height
        xy = cam_pts[:, :2] / np.maximum(cam_pts[:, 2:3], 1e-3)
        if np.any(cam_pts[:, 2] < NEAR):
            x0, y0, x1, y1 = 0, 0, w, h
        else:
            # rays outside the image: pulled in to its edge (the lens model folds past it)
            radius = np.linalg.norm(xy, axis=1, keepdims=True)
            reach = self.canvas.undistorted_reach
            xy = xy * np.minimum(1.0, reach / np.maximum(radius, 1e-12))
            K = self.camera.K
            uv = distort(xy, self.camera.D) * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]
            x0, y0 = np.floor(uv.min(axis=0)).astype(int) - 3
            x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 3
        pad = int(np.ceil(3 * self.sigma)) + 1

        def clipped(p):
            return max(y0 - p, 0), max(x0 - p, 0), min(y1 + p, h), min(x1 + p, w)

        paste, window = clipped(pad), clipped(2 * pad)
        if paste[2] <= paste[0] or paste[3] <= paste[1]:
            return None
        wy0, wx0, wy1, wx1 = window
        mx, my = self.canvas.map_x[wy0:wy1, wx0:wx1], self.canvas.map_y[wy0:wy1, wx0:wx1]
        cw, ch = self.canvas.size
        canvas = (max(int(my.min()) - 2, 0), max(int(mx.min()) - 2, 0),
                  min(int(my.max()) + 3, ch), min(int(mx.max()) + 3, cw))
        return window, paste, canvas

    # -- painting ---------------------------------------------------------------------------
    def _cast_shadow(self, painter: Painter, state: MovingState):
        """Darkens the painter's image where the sponge, hand and arm shade the table."""
        outline = self._on_table(state.vertices)
        palm = self._on_table(state.hand.palm.surface_points())
        limbs = [(self._on_table(np.array([limb.p0, limb.p1])), limb)
                 for limb in state.hand.arm + state.hand.hand]
        ends = np.vstack([outline, palm] + [e for e, _ in limbs])
        pixels = painter.to_pixels(ends)
        blur = max(1.0, 0.006 * self.canvas.focal())
        depth = float(self.canvas.project(state.centre)[1])
        pad = int(3 * blur + 0.08 * self.canvas.focal() / max(0.3, depth))
        h, w = painter.image.shape[:2]
        x0, y0 = np.maximum(np.floor(pixels.min(axis=0)).astype(int) - pad, 0)
        x1, y1 = np.minimum(np.ceil(pixels.max(axis=0)).astype(int) + pad, [w, h])
        if x1 <= x0 or y1 <= y0:
            return
        local = Painter(self.canvas, painter.image[y0:y1, x0:x1],
                        painter.origin + [x0, y0], self.light)
        mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
        local.silhouette(outline, mask)
        local.silhouette(palm, mask)
        for (p0, p1), limb in limbs:
            local.capsule(p0, p1, limb.r0, limb.r1, 255, target=mask)
        mask = cv2.GaussianBlur(mask, (0, 0), blur)
        strength = 0.75 * self.light.diffuse / (self.light.ambient + self.light.diffuse)
        gain = cv2.merge([255 - cv2.convertScaleAbs(mask, alpha=strength)] * 3)
        cv2.multiply(local.image, gain, dst=local.image, scale=1 / 255.0)

    def _paint_moving(self, painter: Painter, state: MovingState):
        hidden, shown = [], []
        for limb, normal, point in state.hand.fingers:
            (shown if painter.facing(point, normal) else hidden).append(limb)
        for limb in hidden:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, limb.colour)
        painter.solid(state.faces, self.sponge_colours)
        self._pores(painter, state)
        for limb in state.hand.arm + state.hand.hand:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, limb.colour)
        painter.ellipsoid(state.hand.palm)
        for limb in shown + state.occluder:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, limb.colour)

    def _pores(self, painter: Painter, state: MovingState):
        pixels = painter.to_pixels(state.vertices)
        h, w = painter.image.shape[:2]
        x0, y0 = np.maximum(np.floor(pixels.min(axis=0)).astype(int), 0)
        x1, y1 = np.minimum(np.ceil(pixels.max(axis=0)).astype(int) + 1, [w, h])
        size = self.pores.shape[0]
        if x1 <= x0 or y1 <= y0 or x1 - x0 > size or y1 - y0 > size:
            return
        mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
        hull = cv2.convexHull((pixels - [x0, y0]).astype(np.float32))[:, 0, :]
        painter.fill_pixels(hull, 255, mask)
        region = painter.image[y0:y1, x0:x1]
        gain = self.pores[:y1 - y0, :x1 - x0]
        shaded = np.clip(region * gain[..., None], 0, 255).astype(np.uint8)
        np.copyto(region, shaded, where=mask[..., None] > 127)

    def visible_fraction(self, state: MovingState) -> float:
        """Share of the sponge's silhouette the free arm leaves visible at this instant."""
        if not state.occluder:
            return 1.0
        uv, _ = self.canvas.project(state.vertices)
        x0, y0 = np.floor(uv.min(axis=0)).astype(int) - 2
        x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 2
        painter = Painter(self.canvas, None, (x0, y0), self.light)
        sponge = np.zeros((y1 - y0, x1 - x0), np.uint8)
        painter.silhouette(state.vertices, sponge)
        cover = np.zeros_like(sponge)
        for limb in state.occluder:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, 255, target=cover)
        inside = sponge > 127
        total = np.count_nonzero(inside)
        if total == 0:
            return 0.0
        return float(np.count_nonzero(inside & (cover <= 127)) / total)

    def render(self, states: list[MovingState]) -> np.ndarray:
        """The frame (BGR uint8, before lighting, noise and codec) averaging ``states``."""
        frame = self.background.copy()
        window = self._window(states)
        if window is None:
            return frame
        (y0, x0, y1, x1), (py0, px0, py1, px1), (cy0, cx0, cy1, cx1) = window
        base = self.static[cy0:cy1, cx0:cx1].copy()
        origin = (cx0, cy0)
        self._cast_shadow(Painter(self.canvas, base, origin, self.light), states[len(states) // 2])
        if len(states) == 1:
            self._paint_moving(Painter(self.canvas, base, origin, self.light), states[0])
            average = base
        else:
            total = np.zeros(base.shape, np.float32)
            for state in states:
                work = base.copy()
                self._paint_moving(Painter(self.canvas, work, origin, self.light), state)
                cv2.accumulate(work, total)
            average = cv2.convertScaleAbs(total, alpha=1.0 / len(states))
        out = self._resample(average, y0, x0, y1, x1, origin)
        frame[py0:py1, px0:px1] = out[py0 - y0:py1 - y0, px0 - x0:px1 - x0]
        return frame


class SceneRenderer:
    """Renders a planned scene frame by frame: (left, right, truth row)."""

    def __init__(self, plan):
        self.plan = plan
        fx = plan.cameras.K1[0][0]
        scale = 1.5 if plan.small else 1.0
        rng = np.random.default_rng([plan.seed, 101])
        e = plan.effects
        self.light = Light(np.array(e.light_direction), e.ambient, 1.0 - e.ambient, e.light_gain)
        px_per_m = float(np.clip(scale * fx / max(plan.cameras.distance, 0.6), 400, 1400))
        tex = StaticTextures(plan, rng, px_per_m)
        pores = textures.pores(rng, 512)
        self.scene = Scene(plan)
        self.views = [CameraView(cam, plan, self.light, tex, pores, scale)
                      for cam in plan.cameras.pair()]
        colours = self.scene.sponge.colours
        for view in self.views:
            view.sponge_colours = colours
        self.fps = plan.video.fps
        self.frame_count = int(round(plan.duration * self.fps))

    def instants(self, t: float) -> list[float]:
        """Times averaged for the frame at t: enough that the sponge and the arm move at most
        :data:`SUBFRAME_STEP_PX` between them."""
        exposure = self.plan.effects.exposure_s
        if exposure <= 0:
            return [t]
        a, b = self.scene.state(t - exposure / 2), self.scene.state(t + exposure / 2)
        cam = self.views[0].camera
        moves = [np.linalg.norm(cam.project(a.centre) - cam.project(b.centre))]
        for la, lb in zip(a.occluder, b.occluder):
            moves.append(np.linalg.norm(cam.project(la.p1) - cam.project(lb.p1)))
        n = int(np.clip(np.ceil(max(moves) / SUBFRAME_STEP_PX), 1, MAX_SUBFRAMES))
        if n == 1:
            return [t]
        return list(t + exposure * (np.arange(n) / (n - 1) - 0.5))

    def frame(self, index: int):
        """(left image, right image, truth row (t, x, y, z, yaw, visible_left, visible_right))."""
        t = index / self.fps
        times = self.instants(t)
        states = [self.scene.state(s) for s in times]
        mid = self.scene.state(t)
        images = [view.render(states) for view in self.views]
        visible = [view.visible_fraction(mid) for view in self.views]
        return images[0], images[1], (t, *mid.centre, mid.yaw, *visible)
