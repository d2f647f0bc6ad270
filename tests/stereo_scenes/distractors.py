"""Static things on the table: where they go and what they look like (plain dicts).

Same-colour distractors (0-3: a cloth, a plate, a bowl, a stain, a cup) take the sponge's
hue; 0-4 other objects take other colours. Flat things (cloth, stain) may lie anywhere,
partly under the wiping area too; solid things never hide any part of the space the sponge
and the holding hand sweep, in either camera.
"""

from __future__ import annotations

import numpy as np

from tests.stereo_scenes.shapes import box_corners
from tests.stereo_scenes.textures import hsv_to_bgr

SAME_COLOUR_KINDS = ("cloth", "plate", "bowl", "stain", "cup")
OTHER_KINDS = ("box", "bottle", "fruit", "mug", "plate", "cloth")
FLAT = ("cloth", "stain")


def _size(kind: str, rng) -> dict:
    if kind == "cloth":
        side = rng.uniform(0.5, 0.9) if rng.random() < 0.25 else rng.uniform(0.18, 0.45)
        return {"length": side, "width": side * rng.uniform(0.5, 1.0),
                "folds": int(rng.integers(1, 5))}
    if kind == "stain":
        return {"radius": rng.uniform(0.02, 0.07), "opacity": rng.uniform(0.35, 0.7)}
    if kind == "plate":
        return {"radius": rng.uniform(0.09, 0.14), "height": rng.uniform(0.012, 0.022)}
    if kind == "bowl":
        return {"radius": rng.uniform(0.06, 0.11), "height": rng.uniform(0.045, 0.08)}
    if kind in ("cup", "mug"):
        return {"radius": rng.uniform(0.032, 0.045), "height": rng.uniform(0.07, 0.11)}
    if kind == "bottle":
        return {"radius": rng.uniform(0.03, 0.045), "height": rng.uniform(0.15, 0.28)}
    if kind == "fruit":
        return {"radius": rng.uniform(0.03, 0.045)}
    if kind == "box":
        return {"length": rng.uniform(0.1, 0.25), "width": rng.uniform(0.06, 0.18),
                "height": rng.uniform(0.03, 0.22)}
    raise ValueError(kind)


def bounding_points(item: dict, table_z: float) -> np.ndarray:
    """Corners (8, 3) of a box around a distractor, world metres."""
    x, y = item["xy"]
    if "length" in item:
        half = np.array([item["length"], item["width"], 0.0]) / 2
        c, s = np.cos(item["yaw"]), np.sin(item["yaw"])
        r = abs(c) * half[0] + abs(s) * half[1], abs(s) * half[0] + abs(c) * half[1]
    else:
        r = (item["radius"], item["radius"])
    top = item.get("height", 2 * item.get("radius", 0.0) if item["kind"] == "fruit" else 0.004)
    corners = box_corners(np.array([r[0], r[1], top / 2]))
    return corners + [x, y, table_z + top / 2]


def _overlap(a, b, margin) -> bool:
    return not (a[2] + margin < b[0] or b[2] + margin < a[0] or
                a[3] + margin < b[1] or b[3] + margin < a[1])


def _bbox(cam, points):
    uv = cam.project(points)
    return (*uv.min(axis=0), *uv.max(axis=0))


def plan_distractors(rng, sponge_hsv, footprint: np.ndarray, table, cameras) -> list[dict]:
    """Distractor dicts: kind, xy, yaw, size keys, bgr, same_colour, overlaps_wiping_area."""
    count = int(rng.choice(4, p=[0.2, 0.35, 0.3, 0.15]))
    kinds = [(str(k), True) for k in rng.choice(SAME_COLOUR_KINDS, count,
                                                 p=[0.35, 0.2, 0.15, 0.15, 0.15])]
    kinds += [(str(k), False) for k in rng.choice(OTHER_KINDS, int(rng.integers(0, 5)))]
    foot_boxes = [_bbox(cam, footprint) for cam in cameras]
    fx0, fy0 = footprint[:, :2].min(axis=0)
    fx1, fy1 = footprint[:, :2].max(axis=0)
    placed = []
    for kind, same in kinds:
        item = {"kind": kind, "same_colour": same, "yaw": float(rng.uniform(0, np.pi)),
                **_size(kind, rng)}
        hsv = _colour(kind, same, sponge_hsv, rng)
        item["hsv"], item["bgr"] = [float(v) for v in hsv], list(hsv_to_bgr(hsv))
        overlap = kind in FLAT and rng.random() < 0.35
        nearby = same and not overlap and rng.random() < 0.4
        for _ in range(60):
            if overlap:
                xy = np.array([rng.uniform(fx0, fx1), rng.uniform(fy0, fy1)])
                xy += rng.normal(size=2) * 0.1
            elif nearby:   # just beside the wiping area
                side = rng.uniform(0.08, 0.3)
                xy = np.array([rng.uniform(fx0 - side, fx1 + side),
                               rng.choice([fy0 - side, fy1 + side])])
                if rng.random() < 0.5:
                    xy = np.array([rng.choice([fx0 - side, fx1 + side]),
                                   rng.uniform(fy0 - side, fy1 + side)])
            else:
                xy = np.array([rng.uniform(table.x_near + 0.05, table.x_far - 0.05),
                               rng.uniform(table.y_min + 0.05, table.y_max - 0.05)])
            item["xy"] = [float(v) for v in xy]
            pts = bounding_points(item, table.height)
            if not _on_table(pts, table):
                continue
            ground = (fx0 - 0.02 < pts[:, 0].max() and pts[:, 0].min() < fx1 + 0.02 and
                      fy0 - 0.02 < pts[:, 1].max() and pts[:, 1].min() < fy1 + 0.02)
            if kind not in FLAT:
                if ground or any(np.any(cam.to_camera(pts)[:, 2] < 0.1) for cam in cameras):
                    continue
                if any(_overlap(_bbox(cam, pts), box, 6) for cam, box in zip(cameras, foot_boxes)):
                    continue
            elif ground != overlap:
                continue
            item["overlaps_wiping_area"] = bool(ground)
            placed.append(item)
            break
    return placed


def _on_table(points: np.ndarray, table) -> bool:
    return bool(np.all((points[:, 0] > table.x_near) & (points[:, 0] < table.x_far) &
                       (points[:, 1] > table.y_min) & (points[:, 1] < table.y_max)))


def _colour(kind: str, same: bool, sponge_hsv, rng):
    if same:
        hue = (sponge_hsv[0] + rng.uniform(-4, 4)) % 180
        if kind == "stain":
            return hue, sponge_hsv[1] * rng.uniform(0.5, 0.9), sponge_hsv[2] * rng.uniform(0.6, 0.9)
        return hue, min(255.0, sponge_hsv[1] * rng.uniform(0.85, 1.05)), \
            min(255.0, sponge_hsv[2] * rng.uniform(0.8, 1.05))
    while True:
        hue = rng.uniform(0, 179)
        d = abs(hue - sponge_hsv[0]) % 180
        if min(d, 180 - d) > 15:
            break
    return hue, rng.uniform(60, 240), rng.uniform(80, 235)
