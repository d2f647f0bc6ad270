"""What moves: the sponge, the demonstrator's arm and hand holding it, and the free arm that
passes between the cameras and the sponge (the occluder). Geometry only (world metres).

Limbs are tapered capsules. Arm lengths and radii are scaled adult sizes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tests.stereo_scenes.shapes import bevelled_box_faces, split_faces_at_height

UPPER_ARM = 0.29
FOREARM = 0.26


@dataclass
class Limb:
    """A tapered capsule from ``p0`` (radius ``r0``) to ``p1`` (radius ``r1``)."""

    p0: np.ndarray
    p1: np.ndarray
    r0: float
    r1: float
    colour: tuple


class SpongeModel:
    """The sponge: a bevelled box, its lower ``pad_fraction`` of the height a scouring pad.

    The sponge frame has its origin at the box centre, x along the length, z up.
    """

    def __init__(self, spec):
        self.half = np.array([spec.length, spec.width, spec.height]) / 2
        faces = bevelled_box_faces(self.half, spec.bevel)
        if spec.pad:
            below, above = split_faces_at_height(faces, -self.half[2] + spec.pad_fraction * spec.height)
            self.faces = below + above
            self.colours = [spec.pad_bgr] * len(below) + [spec.body_bgr] * len(above)
        else:
            self.faces, self.colours = faces, [spec.body_bgr] * len(faces)
        self.vertices = np.unique(np.vstack([p for p, _ in faces]).round(9), axis=0)

    def world_faces(self, centre, R):
        """Faces (polygon (k, 3), normal (3,)) in the world for a pose."""
        return [(poly @ R.T + centre, R @ n) for poly, n in self.faces]

    def world_vertices(self, centre, R) -> np.ndarray:
        """The silhouette's vertices (n, 3) in the world."""
        return self.vertices @ R.T + centre


def _unit(v):
    return v / np.linalg.norm(v)


def shoulder_of(person, table_z: float, holding: bool) -> np.ndarray:
    """A shoulder's position (world) of the person standing behind the table, facing -x."""
    side = 1.0 if person.handed == "right" else -1.0
    if not holding:
        side = -side
    return np.array([person.x - 0.02, person.y + side * 0.19, table_z + person.shoulder_height])


def two_link_elbow(shoulder, wrist, upper, fore, pole) -> tuple[np.ndarray, np.ndarray]:
    """(shoulder, elbow) of an arm reaching ``wrist``; the shoulder leans in when out of reach."""
    span = wrist - shoulder
    d = np.linalg.norm(span)
    reach = 0.97 * (upper + fore)
    if d > reach:
        shoulder = wrist - span / d * reach
        span, d = wrist - shoulder, reach
    u = span / d
    along = (upper ** 2 - fore ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(max(upper ** 2 - along ** 2, 0.0))
    perp = pole - np.dot(pole, u) * u
    perp = _unit(perp) if np.linalg.norm(perp) > 1e-6 else np.array([0, 0, -1.0])
    return shoulder, shoulder + along * u + h * perp


@dataclass
class Ellipsoid:
    """An ellipsoid (the back of a hand): ``centre`` (3,), ``axes`` (3, 3) unit columns,
    ``radii`` (3,) metres along them."""

    centre: np.ndarray
    axes: np.ndarray
    radii: np.ndarray
    colour: tuple

    def surface_points(self) -> np.ndarray:
        """Points (n, 3) spread over the surface (enough for its outline)."""
        return self.centre + (UNIT_SPHERE * self.radii) @ self.axes.T


def _unit_sphere(rings: int = 7, segments: int = 16) -> np.ndarray:
    polar = np.linspace(0, np.pi, rings)[:, None]
    azimuth = np.linspace(0, 2 * np.pi, segments, endpoint=False)[None, :]
    return np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth),
                     np.cos(polar) * np.ones_like(azimuth)], axis=-1).reshape(-1, 3)


UNIT_SPHERE = _unit_sphere()


@dataclass
class HoldingHand:
    """The holding arm and hand for one sponge pose.

    ``fingers`` are (limb, outward normal of the sponge face it lies on, point on that face);
    a finger on a face turned away from a camera is drawn before the sponge.
    """

    arm: list           # upper arm, forearm (drawn after the sponge)
    hand: list          # wrist (drawn after the sponge)
    palm: Ellipsoid     # the back of the hand on the top face
    fingers: list


def grip(person, poses, table_z: float) -> np.ndarray:
    """The direction (sponge frame, unit (3,) along one of its horizontal axes) in which the
    holding hand points, kept for the whole demonstration as a person keeps their grip: the
    sponge axis closest to "away from the shoulder" in most of ``poses`` ((centre, R) pairs
    over the demonstration)."""
    shoulder = shoulder_of(person, table_z, holding=True)
    votes = {}
    for centre, R in poses:
        away = centre - shoulder
        away_local = R.T @ _unit(np.array([away[0], away[1], 0.0]))
        axis = int(np.argmax(np.abs(away_local[:2])))
        key = (axis, float(np.sign(away_local[axis])))
        votes[key] = votes.get(key, 0) + 1
    axis, sign = max(votes, key=lambda key: (votes[key], key))
    direction = np.zeros(3)
    direction[axis] = sign
    return direction


def holding_hand(person, sponge_model: SpongeModel, centre, R, table_z: float,
                 f_local: np.ndarray) -> HoldingHand:
    """Arm and hand gripping the sponge at pose (centre, R).

    The hand points along ``f_local`` (sponge frame, see :func:`grip`): the palm lies on the
    rear part of the top face (``person.palm_offset`` of its length), the four fingers wrap
    over one side and the thumb over the other, the forearm rises to the elbow.
    """
    s = person.hand_scale
    half = sponge_model.half
    c = half[2]
    shoulder = shoulder_of(person, table_z, holding=True)
    axis = int(np.argmax(np.abs(f_local[:2])))
    l_local = np.cross([0, 0, 1.0], f_local)
    along, across = half[axis], half[1 - axis]
    thumb_side = 1.0 if person.handed == "right" else -1.0
    palm_length, palm_r = 0.07 * s, 0.024 * s
    front = -along + person.palm_offset * 2 * along
    palm = f_local * (front - 0.5 * palm_length)
    palm[2] = c

    def world(p):
        return R @ p + centre

    skin = person.skin_bgr
    back = Ellipsoid(world(palm + [0, 0, 0.017 * s]),
                     R @ np.column_stack([f_local, l_local, [0, 0, 1.0]]),
                     np.array([0.047, 0.042, 0.019]) * s, skin)
    wrist = palm - 0.075 * s * f_local + [0, 0, 0.032 * s]
    hand = [Limb(world(wrist), world(palm - 0.03 * s * f_local + [0, 0, palm_r]),
                 0.026 * s, 0.028 * s, skin)]

    fingers = []
    finger_r = 0.0085 * s
    finger_side = -thumb_side
    for offset in (-0.006, 0.012, 0.03, 0.048):
        start = palm + (offset - 0.01) * s * f_local + finger_side * 0.015 * s * l_local
        fingers.extend(_finger(start, finger_side * l_local, half, finger_r,
                               across + 0.05 * s, skin, world, R))
    thumb_start = palm - 0.01 * s * f_local + thumb_side * 0.02 * s * l_local
    fingers.extend(_finger(thumb_start, thumb_side * l_local + 0.4 * f_local, half,
                           0.0095 * s, across + 0.03 * s, skin, world, R))

    sleeve = person.sleeve_bgr if person.sleeve == "long" else skin
    extra = 0.008 if person.sleeve == "long" else 0.0
    wrist_w = world(wrist)
    side_world = np.array([0, 1.0 if person.handed == "right" else -1.0, 0])
    _, elbow = two_link_elbow(shoulder, wrist_w, UPPER_ARM * s, FOREARM * s,
                              side_world + np.array([0, 0, -0.6]))
    if elbow[2] < table_z + 0.07:
        _, elbow = two_link_elbow(shoulder, wrist_w, UPPER_ARM * s, FOREARM * s,
                                  side_world + np.array([0, 0, 0.3]))
    shoulder_now, elbow = two_link_elbow(shoulder, wrist_w, UPPER_ARM * s, FOREARM * s,
                                         elbow - shoulder)
    arm = [Limb(shoulder_now, elbow, 0.05 * s, 0.043 * s, person.shirt_bgr),
           Limb(elbow, wrist_w, (0.037 + extra) * s, (0.027 + extra) * s, sleeve)]
    return HoldingHand(arm, hand, back, fingers)


def _finger(start, direction, half, radius, length, colour, world, R):
    """Segments of a finger from ``start`` (on the top face) along ``direction``, bending down
    over the edge it reaches; returns [(limb, face normal (world), face point (world))]."""
    a, b, c = half
    direction = _unit(np.array([direction[0], direction[1], 0.0]))
    lift = np.array([0, 0, c + radius * 0.9])
    start = np.array([start[0], start[1], 0.0])
    ts = []
    for axis, half in ((0, a), (1, b)):
        if abs(direction[axis]) > 1e-9:
            ts.append(((np.sign(direction[axis]) * half - start[axis]) / direction[axis], axis))
    t_edge, axis = min(ts)
    normal_local = np.zeros(3)
    normal_local[axis] = np.sign(direction[axis])
    if t_edge > length:
        tip = start + direction * length
        return [(Limb(world(start + lift), world(tip + lift), radius, radius * 0.9, colour),
                 R @ np.array([0, 0, 1.0]), world(tip + lift))]
    edge = start + direction * t_edge + normal_local * radius * 0.8
    down = min(length - t_edge, 1.2 * c)
    tip = edge - np.array([0, 0, down]) + lift - [0, 0, radius]
    return [(Limb(world(start + lift), world(edge + lift), radius, radius, colour),
             R @ np.array([0, 0, 1.0]), world(edge + lift)),
            (Limb(world(edge + lift), world(tip), radius, radius * 0.85, colour),
             R @ normal_local, world(tip))]


def free_arm(event, t: float, sponge_centre, eye_mid, camera_right, person) -> list:
    """The occluding arm at time t of an occlusion event (empty outside it).

    The arm lies across the line of sight from the cameras' midpoint to the sponge, at
    ``event.depth_fraction`` of the way to the cameras, parallel to the cameras' baseline,
    its elbow on the line of sight when it covers. It comes in sideways (from above or below
    in the image, ``event.entry``): fast until its edge reaches the sponge, slowly across it
    (the partial occlusion going in), then to ``event.hold_offset`` (0 covers fully); it
    leaves the same way.
    """
    if not event.start <= t <= event.end:
        return []
    s = person.hand_scale
    sight = eye_mid - sponge_centre
    distance = np.linalg.norm(sight)
    sight /= distance
    aim = sponge_centre + event.depth_fraction * distance * sight
    axis = camera_right - np.dot(camera_right, sight) * sight
    axis = event.side * _unit(axis)
    up = np.cross(sight, axis) * event.entry
    if t < event.covered_from:
        x = (t - event.start) / (event.covered_from - event.start)
    elif t > event.covered_to:
        x = (event.end - t) / (event.end - event.covered_to)
    else:
        x = 1.0
    edge, half = event.edge, event.sponge_half
    offset = np.interp(x, [0.0, 0.3, 0.85, 1.0],
                       [edge + half + 0.15, edge + 1.3 * half, max(edge - 1.3 * half,
                                                                  event.hold_offset),
                        event.hold_offset])
    elbow = aim + offset * up
    wrist = elbow + FOREARM * s * axis - 0.01 * up
    shoulder = elbow + 5.0 * UPPER_ARM * s * _unit(-axis + 0.35 * sight)  # out of view
    sleeve = person.sleeve_bgr if person.sleeve == "long" else person.skin_bgr
    extra = 0.008 if person.sleeve == "long" else 0.0
    skin = person.skin_bgr
    knuckles = wrist + 0.085 * s * axis
    limbs = [Limb(shoulder, elbow, 0.05 * s, 0.043 * s, person.shirt_bgr),
             Limb(elbow, wrist, (0.038 + extra) * s, (0.029 + extra) * s, sleeve),
             Limb(wrist, knuckles, 0.03 * s, 0.036 * s, skin),
             Limb(wrist + 0.03 * s * (axis + up), wrist + 0.07 * s * axis + 0.06 * s * up,
                  0.011 * s, 0.009 * s, skin)]                                 # thumb
    for spread in (-1.5, -0.5, 0.5, 1.5):
        base = knuckles + spread * 0.018 * s * up
        tip = base + (0.075 - 0.008 * abs(spread)) * s * _unit(axis + 0.08 * spread * up)
        limbs.append(Limb(base, tip, 0.0095 * s, 0.008 * s, skin))             # fingers
    return limbs
