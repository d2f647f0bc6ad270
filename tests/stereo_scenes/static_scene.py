"""What does not move: room, table, the demonstrator's body, things on the table.

:func:`draw_static` paints them into a camera's whole canvas, back to front: wall, floor,
the person's body, table legs and edges, table top, flat things on it, soft shadows of the
solid things, then the solid things from far to near.
"""

from __future__ import annotations

import cv2
import numpy as np

from tests.stereo_scenes import textures
from tests.stereo_scenes.actors import Limb, shoulder_of
from tests.stereo_scenes.raster import Painter, plane_mapping
from tests.stereo_scenes.distractors import bounding_points
from tests.stereo_scenes.shapes import bevelled_box_faces, horizontal_circle

UP = np.array([0, 0, 1.0])


class StaticTextures:
    """The scene's textures, drawn once per scene and shared by both cameras."""

    def __init__(self, plan, rng, px_per_m: float):
        table = plan.table
        self.px_per_m = px_per_m
        size = (table.x_far - table.x_near, table.y_max - table.y_min)
        self.table = textures.table_texture(table.texture, rng, size, px_per_m, table.hsv,
                                            table.second_hsv)
        coarse = 150.0
        self.coarse = coarse
        self.wall = textures.painted_wall(rng, (8.0, 3.0), coarse, table.wall_hsv)
        floor_kind = "wood" if rng.random() < 0.5 else "tiles"
        floor_fn = textures.wood if floor_kind == "wood" else textures.tiles
        self.floor = floor_fn(rng, (table.wall_x + 3.0, 8.0), coarse, table.floor_hsv)
        self.cloths = []
        for item in plan.distractors:
            if item["kind"] == "cloth":
                hsv = item["hsv"]
                self.cloths.append(textures.towel(rng, (item["length"], item["width"]),
                                                  min(px_per_m, 1200.0), hsv, item["folds"]))
            else:
                self.cloths.append(None)
        self.corner_jitter = [rng.uniform(-0.12, 0.12, (4, 2)) for _ in plan.distractors]
        self.stain_wobble = [rng.uniform(0.6, 1.3, 12) for _ in plan.distractors]


def draw_static(painter: Painter, plan, tex: StaticTextures):
    """Paints the static scene into the painter's (whole-canvas) image."""
    table = plan.table
    light = painter.light
    z = table.height
    painter.image[:] = light.shade(textures.hsv_to_bgr(table.wall_hsv), np.array([-1.0, 0, 0]))
    wall_origin = np.array([table.wall_x, 4.0, 3.0])
    painter.textured_plane(
        tex.wall, plane_mapping(wall_origin, [0, -1.0, 0], [0, 0, -1.0], 1 / tex.coarse),
        np.array([[table.wall_x, 4, 3], [table.wall_x, -4, 3], [table.wall_x, -4, 0],
                  [table.wall_x, 4, 0]]), shade=light.gain * (light.ambient + 0.3 * light.diffuse))
    floor_origin = np.array([-3.0, -4.0, 0.0])
    painter.textured_plane(
        tex.floor, plane_mapping(floor_origin, [1.0, 0, 0], [0, 1.0, 0], 1 / tex.coarse),
        np.array([[-3, -4, 0], [table.wall_x, -4, 0], [table.wall_x, 4, 0], [-3, 4, 0.0]]),
        shade=light.gain * (light.ambient + light.diffuse * light.direction[2]) * 0.85)
    _draw_person(painter, plan.person, z)
    edge = tuple(0.55 * c for c in textures.hsv_to_bgr(table.hsv))
    if table.texture in ("cloth", "checkered"):
        edge = tuple(0.8 * c for c in textures.hsv_to_bgr(table.hsv))
    for x in (table.x_near + 0.05, table.x_far - 0.05):
        for y in (table.y_min + 0.05, table.y_max - 0.05):
            _box(painter, np.array([x, y, (z - table.thickness) / 2]),
                 np.array([0.025, 0.025, (z - table.thickness) / 2]), edge)
    _box(painter, np.array([(table.x_near + table.x_far) / 2, (table.y_min + table.y_max) / 2,
                            z - table.thickness / 2]),
         np.array([(table.x_far - table.x_near) / 2, (table.y_max - table.y_min) / 2,
                   table.thickness / 2]), edge, top=False)
    top = np.array([[table.x_near, table.y_min, z], [table.x_far, table.y_min, z],
                    [table.x_far, table.y_max, z], [table.x_near, table.y_max, z]])
    top_shade = light.gain * (light.ambient + light.diffuse * light.direction[2])
    painter.textured_plane(tex.table, plane_mapping(top[0], [1.0, 0, 0], [0, 1.0, 0],
                                                    1 / tex.px_per_m), top, shade=top_shade)
    for item, cloth, jitter, wobble in zip(plan.distractors, tex.cloths, tex.corner_jitter,
                                           tex.stain_wobble):
        if item["kind"] == "cloth":
            _draw_cloth(painter, item, cloth, jitter, z, top_shade)
        elif item["kind"] == "stain":
            _draw_stain(painter, item, wobble, z, top_shade)
    solids = [item for item in plan.distractors if item["kind"] not in ("cloth", "stain")]
    _draw_shadows(painter, solids, z)
    eye = painter.eye
    solids.sort(key=lambda item: -np.hypot(item["xy"][0] - eye[0], item["xy"][1] - eye[1]))
    for item in solids:
        DRAW_SOLID[item["kind"]](painter, item, z)


def _box(painter, centre, half, colour, top=True, bevel=0.0):
    faces = bevelled_box_faces(half, bevel)
    faces = [(p + centre, n) for p, n in faces if top or n[2] < 0.99]
    painter.solid(faces, [colour] * len(faces))


def _draw_person(painter, person, table_z):
    """Torso, shoulders, neck, head and the hanging free arm, standing behind the table."""
    shoulder_z = table_z + person.shoulder_height
    torso_top = shoulder_z - 0.02
    torso_bottom = table_z - 0.35
    centre = np.array([person.x + 0.05, person.y, 0.5 * (torso_top + torso_bottom)])
    half = np.array([0.11, 0.2, 0.5 * (torso_top - torso_bottom)])
    _box(painter, centre, half, person.shirt_bgr, bevel=0.06)
    free = shoulder_of(person, table_z, holding=False)
    painter.capsule(free, free + [0.03, 0, -0.3], 0.05, 0.043, person.shirt_bgr)
    neck = np.array([person.x + 0.05, person.y, shoulder_z])
    painter.capsule(neck, neck + [0, 0, 0.12], 0.05, 0.05, person.skin_bgr)
    head = neck + [0.0, 0, 0.22]
    painter.sphere(head + [0.02, 0, 0.02], 0.1, person.hair_bgr)
    painter.sphere(head + [-0.015, 0, -0.01], 0.092, person.skin_bgr)
    painter.sphere(head + [0.01, 0, 0.045], 0.085, person.hair_bgr)


def _draw_cloth(painter, item, texture, jitter, z, shade):
    c, s = np.cos(item["yaw"]), np.sin(item["yaw"])
    hl, hw = item["length"] / 2, item["width"] / 2
    local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]]) * (1 + jitter)
    world_xy = local @ np.array([[c, s], [-s, c]]) + item["xy"]
    corners = np.column_stack([world_xy, np.full(4, z + 0.003)])
    h, w = texture.shape[:2]
    src = np.float32([[0, 0], [w, 0], [w, h], [0, h]])
    H = cv2.getPerspectiveTransform(src, world_xy.astype(np.float32)).astype(np.float64)
    M = np.zeros((4, 3))
    M[0], M[1], M[2] = H[0], H[1], (z + 0.003) * H[2]
    M[3] = H[2]
    painter.textured_plane(texture, M, corners, shade=shade)


def _draw_stain(painter, item, wobble, z, shade):
    angle = np.linspace(0, 2 * np.pi, len(wobble), endpoint=False)
    r = item["radius"] * wobble
    pts = np.column_stack([item["xy"][0] + r * np.cos(angle), item["xy"][1] + r * np.sin(angle),
                           np.full(len(angle), z + 0.0005)])
    pixels = painter._clipped(pts)
    if pixels is None:
        return
    mask = np.zeros(painter.image.shape[:2], np.uint8)
    smooth = cv2.approxPolyDP(pixels.astype(np.float32), 0.5, True)[:, 0, :]
    painter.fill_pixels(smooth, 255, mask)
    mask = cv2.GaussianBlur(mask, (0, 0), 1.5)
    alpha = mask.astype(np.float32)[..., None] * (item["opacity"] / 255.0)
    colour = np.array(item["bgr"], np.float32) * shade
    painter.image[:] = np.clip(painter.image * (1 - alpha) + colour * alpha, 0, 255)


def _draw_shadows(painter, solids, z):
    if not solids:
        return
    mask = np.zeros(painter.image.shape[:2], np.uint8)
    L = painter.light.direction
    for item in solids:
        pts = bounding_points(item, z)
        if item["kind"] in ("fruit", "bottle", "cup", "mug", "bowl", "plate"):
            r = item["radius"]
            pts = np.vstack([horizontal_circle([*item["xy"], z], r),
                             horizontal_circle([*item["xy"], z + item.get("height", 2 * r)], r)])
        flat = pts - np.outer((pts[:, 2] - z) / L[2], L)
        painter.silhouette(flat, mask)
    strength = painter.light.diffuse / (painter.light.ambient + painter.light.diffuse)
    blur = cv2.GaussianBlur(mask, (0, 0), max(1.0, 0.004 * painter.canvas.focal()))
    gain = 1.0 - strength * 0.8 * blur.astype(np.float32)[..., None] / 255.0
    painter.image[:] = np.clip(painter.image * gain, 0, 255)


def _cylinder(painter, centre_bottom, radius, height, colour, inside=None):
    base = np.asarray(centre_bottom, float)
    ring_low = horizontal_circle(base, radius, 32)
    ring_high = horizontal_circle(base + [0, 0, height], radius, 32)
    n = len(ring_low)
    for i in range(n):
        j = (i + 1) % n
        quad = np.array([ring_low[i], ring_low[j], ring_high[j], ring_high[i]])
        normal = quad.mean(axis=0) - base
        normal[2] = 0
        normal /= np.linalg.norm(normal)
        if painter.facing(quad.mean(axis=0), normal):
            painter.polygon(quad, painter.light.shade(colour, normal))
    if painter.facing(base + [0, 0, height], UP):
        painter.polygon(ring_high, painter.light.shade(colour, UP))
        if inside is not None:
            painter.polygon(horizontal_circle(base + [0, 0, height], radius * 0.88, 32),
                            painter.light.shade(inside, UP))


def _plate(painter, item, z):
    base = np.array([*item["xy"], z])
    r, h = item["radius"], item["height"]
    _cylinder(painter, base, r * 0.6, h * 0.4, tuple(0.8 * c for c in item["bgr"]))
    _cylinder(painter, base + [0, 0, h * 0.4], r, h * 0.6, item["bgr"],
              inside=tuple(min(255, 1.05 * c) for c in item["bgr"]))
    painter.polygon(horizontal_circle(base + [0, 0, h], r * 0.6, 32),
                    painter.light.shade(tuple(0.92 * c for c in item["bgr"]), UP))


def _bowl(painter, item, z):
    base = np.array([*item["xy"], z])
    r, h = item["radius"], item["height"]
    rings = [horizontal_circle(base + [0, 0, h * f], r * (0.55 + 0.45 * np.sqrt(f)), 32)
             for f in np.linspace(0, 1, 5)]
    for low, high in zip(rings[:-1], rings[1:]):
        for i in range(len(low)):
            j = (i + 1) % len(low)
            quad = np.array([low[i], low[j], high[j], high[i]])
            normal = np.cross(quad[1] - quad[0], quad[3] - quad[0])
            normal /= np.linalg.norm(normal)
            if np.dot(normal, quad.mean(axis=0) - base - [0, 0, h / 2]) < 0:
                normal = -normal
            if painter.facing(quad.mean(axis=0), normal):
                painter.polygon(quad, painter.light.shade(item["bgr"], normal))
    if painter.facing(base + [0, 0, h], UP):
        painter.polygon(rings[-1], painter.light.shade(tuple(0.7 * c for c in item["bgr"]), UP))
        inner = horizontal_circle(base + [0, 0, h * 0.6], r * 0.6, 32)
        painter.polygon(inner, painter.light.shade(tuple(0.85 * c for c in item["bgr"]), UP))


def _cup(painter, item, z):
    base = np.array([*item["xy"], z])
    r, h = item["radius"], item["height"]
    inside = tuple(0.35 * c for c in item["bgr"]) if item["kind"] == "cup" else (30, 45, 70)
    side = np.array([np.cos(item["yaw"]), np.sin(item["yaw"]), 0.0])
    handle = [Limb(base + side * r + [0, 0, h * 0.75], base + side * (r + 0.025) + [0, 0, h * 0.6],
                   0.006, 0.006, item["bgr"]),
              Limb(base + side * (r + 0.025) + [0, 0, h * 0.6], base + side * r + [0, 0, h * 0.25],
                   0.006, 0.006, item["bgr"])]
    behind = np.dot(painter.eye[:2] - base[:2], side[:2]) < 0
    if behind:
        for limb in handle:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, limb.colour)
    _cylinder(painter, base, r, h, item["bgr"], inside=inside)
    if not behind:
        for limb in handle:
            painter.capsule(limb.p0, limb.p1, limb.r0, limb.r1, limb.colour)


def _bottle(painter, item, z):
    base = np.array([*item["xy"], z])
    r, h = item["radius"], item["height"]
    _cylinder(painter, base, r, h * 0.7, item["bgr"])
    painter.capsule(base + [0, 0, h * 0.7], base + [0, 0, h * 0.95], r * 0.8, r * 0.35,
                    item["bgr"])
    _cylinder(painter, base + [0, 0, h * 0.93], r * 0.38, h * 0.07, (40, 40, 40))


def _fruit(painter, item, z):
    painter.sphere([*item["xy"], z + item["radius"]], item["radius"], item["bgr"])


def _solid_box(painter, item, z):
    half = np.array([item["length"], item["width"], item["height"]]) / 2
    c, s = np.cos(item["yaw"]), np.sin(item["yaw"])
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    centre = np.array([*item["xy"], z + half[2]])
    faces = [(p @ R.T + centre, R @ n) for p, n in bevelled_box_faces(half, 0.003)]
    painter.solid(faces, [item["bgr"]] * len(faces))


DRAW_SOLID = {"plate": _plate, "bowl": _bowl, "cup": _cup, "mug": _cup, "bottle": _bottle,
              "fruit": _fruit, "box": _solid_box}
