"""The randomised plan of one scene: every factor a user's setting can change, from a seed.

Each group of factors draws from its own generator (``default_rng([seed, group])``), so
overriding one factor leaves the others of the same seed as they were. Overrides (keyword
arguments of :func:`plan_scene`) replace a drawn value: ``pattern``, ``frequency_hz``,
``across``, ``colour``, ``body_hue`` (the sponge body's OpenCV hue, 0-179, also outside its
colour's named range, as a user's sponge under their light may be), ``two_tone``, ``table_texture``, ``codec``, ``fps``, ``image_size``,
``hfov_deg``, ``k1``, ``baseline``, ``distance``, ``elevation_deg``, ``azimuth_deg``,
``exposure_s``, ``noise_grey``, ``write_T_world_left``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from tests.stereo_scenes.camera import Camera, look_at, rotation
from tests.stereo_scenes.distractors import plan_distractors
from tests.stereo_scenes.lens import monotonic_radius, undistort
from tests.stereo_scenes.textures import TABLE_TEXTURES, hsv_to_bgr

#: The tracker's named sponge colours: OpenCV HSV box (low, high); red wraps through 0.
NAMED_HSV = {
    "red": ((172, 130, 70), (6, 255, 255)),
    "orange": ((7, 150, 90), (17, 255, 255)),
    "yellow": ((20, 130, 90), (34, 255, 255)),
    "green": ((38, 90, 50), (85, 255, 255)),
    "cyan": ((86, 90, 50), (99, 255, 255)),
    "blue": ((100, 110, 50), (128, 255, 255)),
    "purple": ((129, 80, 50), (150, 255, 255)),
    "pink": ((151, 70, 100), (171, 255, 255)),
}
#: Scouring pads: name -> OpenCV HSV.
PAD_HSV = {
    "dark green": (62, 170, 80), "green": (55, 190, 140), "blue": (110, 180, 120),
    "grey": (100, 10, 110), "black": (0, 0, 35), "white": (30, 12, 225),
    "yellow": (27, 170, 200), "red": (178, 190, 140),
}
#: Pad names whose colour is (near) the named body colour, never paired with it.
PAD_CLASH = {"green": ("dark green", "green"), "blue": ("blue",), "yellow": ("yellow",),
             "red": ("red",), "orange": ("red", "yellow"), "cyan": ("blue",), "pink": ("red",),
             "purple": ()}
SKIN_BGR = [(172, 196, 235), (150, 180, 226), (128, 163, 212), (104, 142, 196),
            (82, 118, 170), (62, 92, 138), (46, 68, 104)]
IMAGE_SIZES = [(640, 480), (800, 600), (960, 540), (1280, 720)]
SMALL_SIZE = (320, 240)
CODECS = ("h264", "mp4v", "mjpg")

GROUPS = ("sponge", "motion", "table", "cameras", "person", "distractors", "occlusions",
          "effects", "video")


@dataclass
class Sponge:
    colour: str
    body_hsv: tuple
    body_bgr: tuple
    length: float
    width: float
    height: float
    pad: str | None                 # scouring pad colour name, None for a one-colour sponge
    pad_bgr: tuple | None
    pad_fraction: float             # share of the height that is pad
    bevel: float


@dataclass
class Motion:
    pattern: str
    frequency_hz: float
    across: float
    aspect: float
    centre_xy: tuple
    orientation: float
    yaw0: float
    still_s: float


@dataclass
class Table:
    texture: str
    hsv: tuple
    second_hsv: tuple | None
    near_hue: bool                  # hue chosen near the sponge's
    height: float
    x_near: float
    x_far: float
    y_min: float
    y_max: float
    thickness: float
    floor_hsv: tuple
    wall_hsv: tuple
    wall_x: float


@dataclass
class Cameras:
    width: int
    height: int
    hfov_deg: float
    K1: list
    D1: list
    K2: list
    D2: list
    T_world_left: list
    T_world_right: list
    distance: float
    elevation_deg: float
    azimuth_deg: float
    roll_deg: float
    baseline: float

    def pair(self) -> tuple[Camera, Camera]:
        return (Camera(self.width, self.height, np.array(self.K1), np.array(self.D1),
                       np.array(self.T_world_left)),
                Camera(self.width, self.height, np.array(self.K2), np.array(self.D2),
                       np.array(self.T_world_right)))


@dataclass
class Person:
    handed: str                     # "right" or "left"
    skin_bgr: tuple
    sleeve: str                     # "long" or "bare"
    sleeve_bgr: tuple
    shirt_bgr: tuple
    hair_bgr: tuple
    x: float
    y: float
    shoulder_height: float          # above the table top
    hand_scale: float
    palm_offset: float              # share of the sponge's length the palm covers from the rear


@dataclass
class Occlusion:
    kind: str                       # "full" or "partial"
    start: float
    covered_from: float             # hold: fully (or most) covered from ..
    covered_to: float               # .. to
    end: float
    depth_fraction: float           # where between sponge (0) and cameras (1) the arm passes
    side: int                       # +1: the hand is on the image's right, -1 left
    entry: int                      # +1: the arm comes in from above in the image, -1 below
    edge: float                     # half-width of the arm where it covers, metres
    sponge_half: float              # half the sponge's size seen in the arm's plane, metres
    hold_offset: float              # arm's offset from the line of sight at the hold; 0 = full


@dataclass
class Effects:
    exposure_s: float
    lens_blur_px: float
    noise_grey: float
    gain_drift: float
    colour_drift: float
    moving_shadow: bool
    light_direction: tuple
    ambient: float
    light_gain: float
    white_balance_left: tuple
    white_balance_right: tuple


@dataclass
class Video:
    codec: str
    writer: str                     # "pyav" or "opencv"
    fps: int
    crf: int | None
    bframes: int | None
    preset: str | None
    bits_per_pixel: float | None


@dataclass
class ScenePlan:
    seed: int
    duration: float
    small: bool
    sponge: Sponge
    motion: Motion
    table: Table
    cameras: Cameras
    person: Person
    distractors: list
    occlusions: list
    effects: Effects
    video: Video
    write_T_world_left: bool
    overrides: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """Every factor, JSON-ready (numpy -> lists), plus ``summary``: the main factors in
        one flat dict (for tables of which factors make the worst scenes)."""
        return _plain({**asdict(self), "summary": self.summary()})

    def summary(self) -> dict:
        """The main factors, flat."""
        same = [d for d in self.distractors if d["same_colour"]]
        return {
            "pattern": self.motion.pattern, "frequency_hz": self.motion.frequency_hz,
            "across_m": self.motion.across, "colour": self.sponge.colour,
            "pad": self.sponge.pad, "sponge_length_m": self.sponge.length,
            "table_texture": self.table.texture, "table_near_hue": self.table.near_hue,
            "same_colour_distractors": [d["kind"] for d in same],
            "same_colour_on_wiping_area": any(d["overlaps_wiping_area"] for d in same),
            "other_objects": len(self.distractors) - len(same),
            "sleeve": self.person.sleeve, "image_size": [self.cameras.width, self.cameras.height],
            "hfov_deg": self.cameras.hfov_deg, "k1": self.cameras.D1[0],
            "baseline_m": self.cameras.baseline, "distance_m": self.cameras.distance,
            "elevation_deg": self.cameras.elevation_deg, "azimuth_deg": self.cameras.azimuth_deg,
            "codec": self.video.codec, "writer": self.video.writer, "fps": self.video.fps,
            "exposure_s": self.effects.exposure_s, "noise_grey": self.effects.noise_grey,
            "gain_drift": self.effects.gain_drift, "moving_shadow": self.effects.moving_shadow,
            "full_occlusions": sum(o.kind == "full" for o in self.occlusions),
            "partial_occlusions": sum(o.kind == "partial" for o in self.occlusions),
            "T_world_left_written": self.write_T_world_left,
        }


def _plain(value):
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (np.floating, float)):
        return round(float(value), 9)
    if isinstance(value, np.integer):
        return int(value)
    return value


class _Overrides:
    """Hands out override values once; what is left unused is an error."""

    def __init__(self, values: dict):
        self.values = dict(values)

    def get(self, name, draw):
        return self.values.pop(name) if name in self.values else draw()

    def check_used(self):
        if self.values:
            raise ValueError(f"unknown scene override(s): {', '.join(sorted(self.values))}")


def hue_distance(a: float, b: float) -> float:
    """Distance of two OpenCV hues (0-179) on the hue circle."""
    d = abs(a - b) % 180
    return min(d, 180 - d)


def _hue_inside(name: str, rng) -> float:
    (h0, _, _), (h1, _, _) = NAMED_HSV[name]
    if h0 > h1:
        h1 += 180
    margin = min(3.0, 0.2 * (h1 - h0))
    return (rng.uniform(h0 + margin, h1 - margin)) % 180


def plan_sponge(rng, o: _Overrides) -> Sponge:
    colour = o.get("colour", lambda: str(rng.choice(list(NAMED_HSV))))
    (_, s0, v0), _ = NAMED_HSV[colour]
    hue = _hue_inside(colour, rng)  # drawn even when overridden: the other draws stay the same
    hsv = (float(o.get("body_hue", lambda: hue)) % 180, rng.uniform(max(s0 + 45, 160), 250),
           rng.uniform(max(v0 + 70, 165), 245))
    length = rng.uniform(0.07, 0.15)
    width = rng.uniform(0.045, min(0.10, 0.9 * length))
    height = rng.uniform(0.015, 0.05)
    two_tone = o.get("two_tone", lambda: bool(rng.random() < 0.6))
    pad = pad_bgr = None
    if two_tone:
        names = [n for n in PAD_HSV if n not in PAD_CLASH[colour]]
        pad = str(rng.choice(names))
        pad_bgr = hsv_to_bgr(PAD_HSV[pad])
    return Sponge(colour, hsv, hsv_to_bgr(hsv), length, width, height, pad, pad_bgr,
                  rng.uniform(0.2, 0.4) if two_tone else 0.0,
                  min(rng.uniform(0.0015, 0.004), 0.08 * height))  # the pad shows on the sides


def plan_motion(rng, o: _Overrides, sponge: Sponge) -> Motion:
    pattern = o.get("pattern", lambda: str(rng.choice(["circle", "line", "figure8", "ellipse"],
                                                      p=[0.3, 0.3, 0.3, 0.1])))
    aspect = {"circle": 1.0, "ellipse": rng.uniform(0.45, 0.8), "line": 0.0,
              "figure8": rng.uniform(0.35, 0.6)}[pattern]
    return Motion(pattern, o.get("frequency_hz", lambda: rng.uniform(0.5, 1.5)),
                  o.get("across", lambda: rng.uniform(0.10, 0.40)), aspect,
                  (0.0, 0.0), rng.uniform(-np.pi / 2, np.pi / 2), _grip_yaw(rng),
                  rng.uniform(0.0, 1.0))


def _grip_yaw(rng) -> float:
    """Mean yaw of the sponge: its long axis towards the person (+x) within 35 degrees, or
    (one time in four) across."""
    yaw = np.radians(rng.uniform(-35, 35))
    return float(yaw + (np.pi / 2 if rng.random() < 0.25 else 0.0))


def footprint_half(motion: Motion, sponge: Sponge) -> tuple[float, float]:
    """Half sizes (along, across the pattern's major axis) of the table area the sponge
    sweeps, metres, with room for wander."""
    reach = 0.5 * motion.across * 1.15 + 0.03
    half_diag = 0.5 * math.hypot(sponge.length, sponge.width)
    minor = {"circle": reach, "ellipse": reach * motion.aspect, "line": 0.1 * reach + 0.02,
             "figure8": reach * motion.aspect}[motion.pattern]
    return reach + half_diag, minor + half_diag


def footprint_points(motion: Motion, sponge: Sponge, table_z: float, top: float) -> np.ndarray:
    """Points (n, 3) bounding the space the sponge and the holding hand sweep."""
    hx, hy = footprint_half(motion, sponge)
    c, s = math.cos(motion.orientation), math.sin(motion.orientation)
    pts = []
    for fx in (-1, 0, 1):
        for fy in (-1, 0, 1):
            x, y = fx * hx, fy * hy
            for z in (table_z, table_z + top):
                pts.append((motion.centre_xy[0] + c * x - s * y,
                            motion.centre_xy[1] + s * x + c * y, z))
    return np.array(pts)


def plan_table(rng, o: _Overrides, sponge: Sponge, motion: Motion) -> tuple[Table, Motion]:
    kind = o.get("table_texture", lambda: str(rng.choice(TABLE_TEXTURES,
                                                         p=[0.3, 0.15, 0.1, 0.1, 0.2, 0.15])))
    body_h = sponge.body_hsv[0]
    near_hue = bool(rng.random() < 0.3)
    second = None
    if kind == "wood":
        if near_hue and sponge.colour in ("yellow", "orange", "red"):
            hue = (body_h + rng.uniform(-4, 4)) % 180
        else:
            hue = rng.uniform(8, 22)
        hsv = (hue, rng.uniform(70, 170), rng.uniform(110, 210))
    elif kind == "laminate":
        hsv = (rng.uniform(0, 179), rng.uniform(0, 40), rng.uniform(170, 235))
    elif kind == "marble":
        hsv = (rng.uniform(0, 179), rng.uniform(0, 18), rng.uniform(200, 240))
    elif kind == "tiles":
        hsv = (rng.uniform(0, 179), rng.uniform(0, 90), rng.uniform(150, 230))
    else:
        s_low = NAMED_HSV[sponge.colour][0][1]
        if near_hue:
            hue = (body_h + rng.uniform(-6, 6)) % 180
            hsv = (hue, rng.uniform(25, max(30, s_low - 30)), rng.uniform(150, 230))
        else:
            hsv = (rng.uniform(0, 179), rng.uniform(20, 200), rng.uniform(120, 235))
        if kind == "checkered":
            second = (hsv[0], rng.uniform(0, 20), rng.uniform(200, 245))
    height = rng.uniform(0.6, 1.0)
    x_near = rng.uniform(0.25, 0.45)
    depth = rng.uniform(0.7, 1.1)
    x_far = x_near + depth
    width = rng.uniform(1.0, 1.8)
    y_c = rng.uniform(-0.2, 0.2)
    hx, hy = footprint_half(motion, sponge)
    c, s = abs(math.cos(motion.orientation)), abs(math.sin(motion.orientation))
    ext_x, ext_y = c * hx + s * hy, s * hx + c * hy
    x_w = x_far - ext_x - rng.uniform(0.08, 0.25)
    x_w = max(x_w, x_near + ext_x + 0.05)
    y_w = y_c + rng.uniform(-1, 1) * max(0.0, 0.5 * width - ext_y - 0.1)
    motion.centre_xy = (float(x_w), float(y_w))
    table = Table(kind, hsv, second, near_hue, height, x_near, x_far, y_c - width / 2,
                  y_c + width / 2, rng.uniform(0.02, 0.05),
                  (rng.uniform(0, 179), rng.uniform(0, 80), rng.uniform(60, 160)),
                  (rng.uniform(0, 179), rng.uniform(0, 50), rng.uniform(150, 235)),
                  x_far + rng.uniform(0.9, 2.5))
    return table, motion


def _intrinsics(rng, width, height, hfov_deg, k1):
    fx = 0.5 * width / math.tan(math.radians(hfov_deg) / 2)
    K = np.array([[fx, 0, width / 2 + rng.uniform(-0.03, 0.03) * width],
                  [0, fx * rng.uniform(0.997, 1.003), height / 2 + rng.uniform(-0.03, 0.03) * height],
                  [0, 0, 1.0]])
    k2 = k1 * k1 * rng.uniform(0.2, 0.7)
    D = np.array([k1, k2, rng.uniform(-0.0015, 0.0015), rng.uniform(-0.0015, 0.0015),
                  rng.uniform(-0.02, 0.02) * abs(k1)])
    corners = np.array([[0, 0], [width, 0], [0, height], [width, height]], float)
    xy_d = (corners - K[:2, 2]) / [K[0, 0], K[1, 1]]
    while True:
        r_corner = np.linalg.norm(undistort(xy_d, D), axis=1).max()
        if monotonic_radius(D) > 1.15 * r_corner and r_corner < 3.0:
            return K, D
        D = D * [0.85, 0.85 ** 2, 1, 1, 0.85]


def plan_cameras(rng, o: _Overrides, small: bool, motion: Motion, sponge: Sponge,
                 table: Table) -> Cameras:
    size = o.get("image_size", lambda: SMALL_SIZE if small else
                 IMAGE_SIZES[int(rng.integers(len(IMAGE_SIZES)))])
    width, height = int(size[0]), int(size[1])
    k1_fixed = "k1" in o.values
    k1_value = o.get("k1", lambda: None)
    fixed = {name: o.get(name, lambda: None)
             for name in ("hfov_deg", "baseline", "distance", "elevation_deg", "azimuth_deg")}
    foot = footprint_points(motion, sponge, table.height, sponge.height + 0.07)
    centre = np.array([*motion.centre_xy, table.height])
    for attempt in range(2000):
        hfov = fixed["hfov_deg"] or rng.uniform(50, 95)
        if k1_fixed:
            k1 = k1_value
        else:
            k1 = 0.0 if rng.random() < 0.15 else -0.45 * rng.uniform(0.05, 1.0)
            k1 *= min(1.0, (hfov - 20) / 45)
        K1, D1 = _intrinsics(rng, width, height, hfov, k1)
        K2 = K1.copy()
        K2[0, 0] *= 1 + rng.uniform(-0.01, 0.01)
        K2[1, 1] = K2[0, 0] * K1[1, 1] / K1[0, 0]
        K2[:2, 2] += rng.uniform(-0.01, 0.01, 2) * [width, height]
        D2 = D1 * (1 + rng.uniform(-0.06, 0.06, 5))
        distance = fixed["distance"] or rng.uniform(0.5, 1.6)
        elevation = math.radians(fixed["elevation_deg"] or rng.uniform(25, 80))
        azimuth = math.radians(fixed["azimuth_deg"] if fixed["azimuth_deg"] is not None
                               else rng.uniform(-40, 40))
        roll = math.radians(rng.uniform(-5, 5))
        baseline = fixed["baseline"] or rng.uniform(0.06, 0.30)
        head = centre + distance * np.array([-math.cos(elevation) * math.cos(azimuth),
                                             -math.cos(elevation) * math.sin(azimuth),
                                             math.sin(elevation)])
        aim = centre + np.array([*rng.uniform(-0.25, 0.25, 2) * distance * 0.5, 0.0])
        T_head = look_at(head, aim, roll)
        toe_in = math.atan(rng.uniform(0.0, 1.0) * 0.5 * baseline / np.linalg.norm(aim - head))
        poses = []
        for sign in (-1, 1):
            T = T_head.copy()
            T[:3, 3] = head + sign * 0.5 * baseline * T_head[:3, 0]
            wobble = rotation(rng.normal(size=3), math.radians(rng.uniform(0, 1.0)))
            T[:3, :3] = T_head[:3, :3] @ rotation([0, 1.0, 0], -sign * toe_in) @ wobble
            poses.append(T)
        cams = (Camera(width, height, K1, D1, poses[0]), Camera(width, height, K2, D2, poses[1]))
        if all(_sees(cam, foot, 0.04) for cam in cams):
            return Cameras(width, height, hfov, K1.tolist(), D1.tolist(), K2.tolist(), D2.tolist(),
                           poses[0].tolist(), poses[1].tolist(), distance, math.degrees(elevation),
                           math.degrees(azimuth), math.degrees(roll), baseline)
    raise ValueError("no camera placement sees the whole wiping area; relax the overrides")


def _sees(cam: Camera, points: np.ndarray, margin: float) -> bool:
    z = cam.to_camera(points)[:, 2]
    if np.any(z < 0.15):
        return False
    xy = cam.to_camera(points)
    r = np.linalg.norm(xy[:, :2] / xy[:, 2:3], axis=1)
    if np.any(r > monotonic_radius(cam.D) / 1.2):
        return False
    uv = cam.project(points)
    m = margin * cam.width
    return bool(np.all((uv[:, 0] > m) & (uv[:, 0] < cam.width - m) &
                       (uv[:, 1] > m) & (uv[:, 1] < cam.height - m)))


def plan_person(rng, motion: Motion, sponge: Sponge, table: Table) -> Person:
    handed = "right" if rng.random() < 0.85 else "left"
    skin = SKIN_BGR[int(rng.integers(len(SKIN_BGR)))]
    skin = tuple(float(np.clip(c * rng.uniform(0.93, 1.07), 0, 255)) for c in skin)
    body_hue = sponge.body_hsv[0]
    while True:
        sleeve_hsv = (rng.uniform(0, 179), rng.uniform(0, 200), rng.uniform(40, 230))
        if sleeve_hsv[1] < 60 or hue_distance(sleeve_hsv[0], body_hue) > 25:
            break
    sleeve = "bare" if rng.random() < 0.3 else "long"
    shirt = hsv_to_bgr(sleeve_hsv)
    side = 1 if handed == "right" else -1            # the person faces -x: right is +y
    return Person(handed, skin, sleeve, shirt, shirt,
                  hsv_to_bgr((rng.uniform(5, 20), rng.uniform(30, 160), rng.uniform(20, 120))),
                  table.x_far + rng.uniform(0.14, 0.24),
                  motion.centre_xy[1] - side * rng.uniform(0.08, 0.2),
                  rng.uniform(0.42, 0.58), rng.uniform(0.9, 1.1),
                  rng.uniform(0.3, 0.55))


def plan_occlusions(rng, duration: float, sponge: Sponge, cameras: Cameras,
                    person: Person) -> list[Occlusion]:
    """At least one full occlusion per started 25 s (the first event is a full one), plus
    0-2 partial ones per 25 s; events do not overlap and start after the first 2 s (or 30 %
    of a short demo).

    The free arm covers the sponge when its narrowest part near the elbow looks wider than
    the sponge's diagonal by a margin: that fixes how far towards the cameras it passes.
    """
    n_full = max(1, math.ceil(duration / 25.0 - 1e-9))
    n_partial = int(rng.integers(0, 1 + int(duration // 12)))
    kinds = ["full"] * n_full + ["partial"] * n_partial
    rng.shuffle(kinds)
    kinds.remove("full")
    kinds.insert(0, "full")
    t_min = min(2.0, 0.3 * duration)
    usable = duration - 0.3 - t_min
    lengths = np.array([[rng.uniform(0.25, 0.5),
                         rng.uniform(0.5, 1.5) if kind == "full" else rng.uniform(0.3, 1.0),
                         rng.uniform(0.25, 0.5)] for kind in kinds])
    while lengths.sum() > 0.85 * usable and "partial" in kinds:
        drop = len(kinds) - 1 - kinds[::-1].index("partial")
        kinds.pop(drop)
        lengths = np.delete(lengths, drop, axis=0)
    if lengths.sum() > 0.85 * usable:
        lengths *= 0.85 * usable / lengths.sum()
        lengths[:, 1] = np.maximum(lengths[:, 1], 0.5)
    free = max(0.0, usable - lengths.sum())
    gaps = rng.dirichlet(np.ones(len(kinds) + 1)) * free
    diag = math.sqrt(sponge.length ** 2 + sponge.width ** 2 + sponge.height ** 2)
    distance = cameras.distance  # cameras' midpoint to the wiping centre
    edge = (0.038 + (0.008 if person.sleeve == "long" else 0.0)) * person.hand_scale
    events, t = [], t_min
    for kind, (t_in, hold, t_out), gap in zip(kinds, lengths, gaps):
        t += gap
        fraction = 1 - 2 * edge / (1.35 * diag) + rng.uniform(0.0, 0.05)
        fraction = float(np.clip(fraction, 0.3, 1 - 0.1 / distance))
        half = 0.5 * diag * (1 - fraction)
        offset = 0.0 if kind == "full" else float(edge + rng.uniform(-0.6, 0.6) * half)
        events.append(Occlusion(kind, t, t + t_in, t + t_in + hold, t + t_in + hold + t_out,
                                fraction, int(rng.choice([-1, 1])), int(rng.choice([-1, 1])),
                                edge, half, offset))
        t += t_in + hold + t_out
    return events


def plan_effects(rng, o: _Overrides, fps: int) -> Effects:
    exposure = o.get("exposure_s", lambda: float(np.exp(rng.uniform(np.log(1 / 500),
                                                                    np.log(1 / 30)))))
    light_el = math.radians(rng.uniform(35, 75))
    light_az = rng.uniform(0, 2 * np.pi)
    direction = (math.cos(light_el) * math.cos(light_az), math.cos(light_el) * math.sin(light_az),
                 math.sin(light_el))
    ambient = rng.uniform(0.35, 0.55)
    diffuse = 1 - ambient
    top = ambient + diffuse * direction[2]
    return Effects(min(exposure, 1.0 / fps), rng.uniform(0.3, 1.1),
                   o.get("noise_grey", lambda: rng.uniform(1, 5)), rng.uniform(0.03, 0.15),
                   rng.uniform(0.02, 0.1), bool(rng.random() < 0.35), direction, ambient,
                   rng.uniform(0.88, 1.02) / top,
                   tuple(rng.uniform(0.95, 1.05, 3)), tuple(rng.uniform(0.95, 1.05, 3)))


def plan_video(rng, o: _Overrides, small: bool) -> Video:
    codec = o.get("codec", lambda: str(rng.choice(CODECS, p=[0.45, 0.35, 0.2])))
    fps = int(o.get("fps", lambda: int(rng.choice([30, 25, 60], p=[0.8, 0.1, 0.1]))))
    if codec == "h264":
        return Video(codec, "pyav", fps, int(rng.integers(18, 29)),
                     int(rng.choice([0, 2, 3], p=[0.6, 0.2, 0.2])),
                     str(rng.choice(["superfast", "veryfast", "faster"])), None)
    if codec not in CODECS:
        raise ValueError(f"unknown codec {codec!r}; expected one of {CODECS}")
    writer = "opencv" if rng.random() < 0.5 else "pyav"
    bpp = None
    if writer == "pyav":
        bpp = rng.uniform(0.05, 0.4) if codec == "mp4v" else rng.uniform(0.3, 1.0)
    return Video(codec, writer, fps, None, None, None, bpp)


def plan_scene(seed: int, duration: float | None = None, small: bool = False,
               **overrides) -> ScenePlan:
    """All the factors of scene ``seed`` (see the module docstring for ``overrides``)."""
    o = _Overrides(overrides)
    rngs = {g: np.random.default_rng([int(seed), i]) for i, g in enumerate(GROUPS)}
    if duration is None:
        duration = rngs["video"].uniform(2.5, 5.0) if small else 32.0
    sponge = plan_sponge(rngs["sponge"], o)
    motion = plan_motion(rngs["motion"], o, sponge)
    table, motion = plan_table(rngs["table"], o, sponge, motion)
    cameras = plan_cameras(rngs["cameras"], o, small, motion, sponge, table)
    person = plan_person(rngs["person"], motion, sponge, table)
    video = plan_video(rngs["video"], o, small)
    effects = plan_effects(rngs["effects"], o, video.fps)
    occlusions = plan_occlusions(rngs["occlusions"], duration, sponge, cameras, person)
    foot = footprint_points(motion, sponge, table.height, sponge.height + 0.08)
    distractors = plan_distractors(rngs["distractors"], sponge.body_hsv, foot, table,
                                   cameras.pair())
    write_pose = o.get("write_T_world_left", lambda: bool(rngs["cameras"].random() < 0.8))
    o.check_used()
    return ScenePlan(int(seed), float(duration), bool(small), sponge, motion, table, cameras,
                     person, distractors, occlusions, effects, video, bool(write_pose),
                     {k: _plain(v) for k, v in overrides.items()})
