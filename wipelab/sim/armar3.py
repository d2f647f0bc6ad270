"""The ARMAR-IIIb description: sourced kinematics, limits, masses and sizes, written as URDF.

Numbers from KIT's Simox model of ARMAR-III (``VirtualRobot/data/robots/ArmarIII``), converted
to URDF convention (x forward, y left, z up, metres; every joint origin with rpy = 0, so all
link frames are parallel to ``base_link`` at q = 0; Simox's joint zeros). ARMAR-IIIb is a copy
of ARMAR-IIIa. Values marked *estimate* below are not sourced. The shipped file
``assets/armar3b.urdf`` is the output of :func:`armar3b_urdf` (a test keeps them equal).

Tree: ``world`` -> platform (x, y prismatic, yaw) -> ``base_link`` (on the floor under the
platform centre) -> hip pitch/roll/yaw -> ``torso`` -> right/left 7-DOF arm -> wrist_2 ->
fixed joint ``ft_sensor_r``/``ft_sensor_l`` (the 6D force/torque sensor at the wrist centre)
-> ``hand_*`` -> fixed ``tcp_*`` 0.130 m along the approach axis; torso -> 7-DOF head
(neck pitch/roll/yaw, head tilt, common eye tilt, two eye pans) with the wide-angle cameras
and their optical frames (x right, y down, z forward).

Zero pose: the upper arm hangs down abducted 15 deg, the elbow is bent 90 deg so the forearm
points forward, the palm faces up tilted 15 deg toward the midline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

#: cos/sin of 15 deg, the tilt that runs through the arm's axes.
_C15, _S15 = math.cos(math.radians(15.0)), math.sin(math.radians(15.0))

#: Name of the robot in the URDF.
ROBOT_NAME = "armar3b"


@dataclass(frozen=True)
class Box:
    """A box collision/visual shape. ``size`` (3,) m; pose of its centre in the link frame."""

    size: tuple[float, float, float]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Cylinder:
    """A cylinder from ``start`` to ``end`` (link frame, m) with ``radius`` (m)."""

    radius: float
    start: tuple[float, float, float]
    end: tuple[float, float, float]


@dataclass(frozen=True)
class Sphere:
    """A sphere of ``radius`` (m) centred at ``xyz`` in the link frame."""

    radius: float
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class LinkSpec:
    """One link: mass (kg), centre of mass (m, link frame), shapes (visual = collision)."""

    name: str
    mass: float
    com: tuple[float, float, float]
    shapes: tuple = ()
    color: str = "grey"


@dataclass(frozen=True)
class JointSpec:
    """One joint: ``kind`` in revolute/prismatic/fixed; origin from the parent frame (m, rpy = 0
    unless given); axis in that (parent-parallel) frame; limits (rad or m); effort (N m or N);
    velocity (rad/s or m/s)."""

    name: str
    kind: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    lower: float = 0.0
    upper: float = 0.0
    effort: float = 0.0
    velocity: float = 1.0
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


#: Right-arm joints from the shoulder to the wrist, in chain order (Simox names, suffix _r).
RIGHT_ARM_JOINTS = ("shoulder_1_r", "shoulder_2_r", "upperarm_r", "elbow_r", "underarm_r",
                    "wrist_1_r", "wrist_2_r")
#: Torso joints, base -> torso.
TORSO_JOINTS = ("hip_pitch", "hip_roll", "hip_yaw")
#: Platform joints (holonomic base), world -> base_link.
PLATFORM_JOINTS = ("platform_x", "platform_y", "platform_yaw")

# Right arm, shoulder -> wrist: (joint, origin from previous joint, axis, limits rad, link mass kg)
_RIGHT_ARM = (
    ("shoulder_1_r", (-0.035, -0.232, 0.485), (0.0, 1.0, 0.0), (-1.8665, 1.3963), 3.65),
    ("shoulder_2_r", (0.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (-0.2417, 1.6514), 2.5),
    ("upperarm_r", (0.0, 0.0, 0.0), (0.0, _S15, _C15), (-1.8869, 1.2905), 1.557),
    ("elbow_r", (0.020, -0.080233, -0.299437), (0.0, -_C15, _S15), (-1.9998, 0.9599), 1.157),
    ("underarm_r", (0.0, -0.007244, 0.001941), (-1.0, 0.0, 0.0), (-1.2156, 1.8893), 2.266),
    ("wrist_1_r", (0.240, 0.0, 0.0), (0.0, -_S15, -_C15), (-0.5093, 0.5215), 1.299),
    ("wrist_2_r", (0.0, 0.0, 0.0), (0.0, _C15, -_S15), (-0.5393, 0.8878), 0.2),
)
# Left arm (Simox limits, deg) and the sign that makes the mirrored axis match those limits:
# +1 where Simox's left range equals the right one, -1 where it is the negated range.
_LEFT_LIMITS_DEG = ((-106.91, 80.0), (-94.62, 13.85), (-69.65, 108.25), (-122.96, 55.0),
                    (-108.25, 69.65), (-29.36, 24.11), (-38.40, 44.32))
_LEFT_AXIS_SIGN = (1.0, -1.0, -1.0, 1.0, -1.0, 1.0, 1.0)

#: Size (m) of the platform's box: length (x), width (y), height; centred on base_link in x-y.
PLATFORM_SIZE = (0.68, 0.68, 0.954)
#: Distance from the wrist centre to the TCP along the approach axis (m).
TCP_OFFSET = 0.130
#: Palm normal of the right hand at q = 0 (faces up, tilted 15 deg toward the midline).
RIGHT_PALM_NORMAL = (0.0, _S15, _C15)
#: Hand mass (kg), *estimate* (Simox's hand masses are placeholders).
HAND_MASS = 1.0


def _mirror_y(v):
    """Mirror a point across the x-z plane (left from right)."""
    return (v[0], -v[1], v[2])


def _mirror_axis(a, sign):
    """Mirror a rotation axis (a pseudo-vector) across the x-z plane, times ``sign``."""
    return (-sign * a[0], sign * a[1], -sign * a[2])


def _arm(side: str) -> tuple[list[JointSpec], list[LinkSpec]]:
    """Joints and links of one arm from ``torso`` to ``tcp_<side>`` (side 'r' or 'l')."""
    right = side == "r"
    point = (lambda v: v) if right else _mirror_y
    joints, links = [], []
    parent = "torso"
    upper_arm_vector = _RIGHT_ARM[3][1]
    for k, (name, xyz, axis, limits, mass) in enumerate(_RIGHT_ARM):
        name = name[:-1] + side
        if right:
            lower, upper = limits
        else:
            axis = _mirror_axis(axis, _LEFT_AXIS_SIGN[k])
            lower, upper = (math.radians(d) for d in _LEFT_LIMITS_DEG[k])
        child = f"{name}_link"
        joints.append(JointSpec(name, "revolute", parent, child, point(xyz), axis, lower, upper,
                                effort=150.0, velocity=1.0))
        if name.startswith("upperarm"):
            shapes = (Cylinder(0.041, (0.0, 0.0, 0.0), point(upper_arm_vector)),)
            com = tuple(0.5 * c for c in point(upper_arm_vector))
        elif name.startswith("underarm"):
            shapes = (Cylinder(0.047, (0.02, 0.0, 0.0), (0.22, 0.0, 0.0)),)
            com = (0.12, 0.0, 0.0)
        elif name.startswith("shoulder_1"):
            shapes = (Sphere(0.06),)
            com = (0.0, 0.0, 0.0)
        elif name.startswith("elbow"):
            shapes = (Sphere(0.045),)
            com = (0.0, 0.0, 0.0)
        elif name.startswith("wrist_2"):
            # the 6D F/T sensor body: a short disc across the forearm axis
            shapes = (Cylinder(0.035, (-0.02, 0.0, 0.0), (0.0, 0.0, 0.0)),)
            com = (-0.01, 0.0, 0.0)
        else:
            shapes = ()
            com = (0.0, 0.0, 0.0)
        links.append(LinkSpec(child, mass, com, shapes, "arm"))
        parent = child
    normal = point(RIGHT_PALM_NORMAL)
    roll = -math.radians(15.0) if right else math.radians(15.0)
    hand = f"hand_{side}"
    joints.append(JointSpec(f"ft_sensor_{side}", "fixed", parent, hand, (0.0, 0.0, 0.0)))
    palm = Box((0.09, 0.07, 0.046), (0.081, 0.0, 0.0), (roll, 0.0, 0.0))
    # fingers, curled toward the palm side: a block past the palm
    fingers = Box((0.07, 0.07, 0.025),
                  (0.161, 0.012 * normal[1], 0.012 * normal[2]), (roll, 0.0, 0.0))
    links.append(LinkSpec(hand, HAND_MASS, (0.09, 0.0, 0.0), (palm, fingers), "hand"))
    joints.append(JointSpec(f"tcp_{side}_joint", "fixed", hand, f"tcp_{side}",
                            (TCP_OFFSET, 0.0, 0.0)))
    links.append(LinkSpec(f"tcp_{side}", 0.0, (0.0, 0.0, 0.0)))
    return joints, links


def _head() -> tuple[list[JointSpec], list[LinkSpec]]:
    """The 7-DOF head with the wide-angle stereo cameras (IVT: pan axes 93 mm apart)."""
    deg45, deg30 = math.radians(45.0), math.radians(30.0)
    joints = [
        JointSpec("neck_1_pitch", "revolute", "torso", "neck_1_link", (-0.035, 0.0, 0.603),
                  (0.0, -1.0, 0.0), -deg45, deg45, 50.0),
        JointSpec("neck_2_roll", "revolute", "neck_1_link", "neck_2_link", (0.0, 0.0, 0.0),
                  (1.0, 0.0, 0.0), -deg45, deg45, 50.0),
        JointSpec("neck_3_yaw", "revolute", "neck_2_link", "neck_3_link", (0.0, 0.0, 0.0),
                  (0.0, 0.0, 1.0), -deg45, deg45, 50.0),
        JointSpec("head_tilt", "revolute", "neck_3_link", "head_link", (0.0, 0.0, 0.120),
                  (0.0, -1.0, 0.0), -deg45, deg45, 50.0),
        JointSpec("eyes_tilt", "revolute", "head_link", "eyes_link", (0.100, 0.0, 0.0545),
                  (0.0, 1.0, 0.0), -deg30, deg45, 10.0),
    ]
    links = [
        LinkSpec("neck_1_link", 1.5, (0.0, 0.0, 0.0), (Sphere(0.04),), "arm"),
        LinkSpec("neck_2_link", 1.5, (0.0, 0.0, 0.0)),
        LinkSpec("neck_3_link", 2.0, (0.0, 0.0, 0.06),
                 (Cylinder(0.04, (0.0, 0.0, 0.0), (0.0, 0.0, 0.12)),), "arm"),
        LinkSpec("head_link", 12.0, (0.0, 0.0, 0.05),
                 (Box((0.20, 0.22, 0.22), (0.0, 0.0, 0.057)),), "head"),
        LinkSpec("eyes_link", 1.0, (0.0, 0.0, 0.0)),
    ]
    for side, y in (("left", 0.0465), ("right", -0.0465)):
        eye = f"eye_{side}_link"
        joints.append(JointSpec(f"eye_{side}", "revolute", "eyes_link", eye, (0.0, y, 0.0),
                                (0.0, 0.0, -1.0), -deg30, deg30, 5.0))
        links.append(LinkSpec(eye, 0.5, (0.0, 0.0, 0.0), (Sphere(0.02),), "eye"))
        camera = f"camera_{side}"
        joints.append(JointSpec(f"camera_{side}_joint", "fixed", eye, camera, (0.020, 0.0, 0.0)))
        links.append(LinkSpec(camera, 0.0, (0.0, 0.0, 0.0)))
        joints.append(JointSpec(f"camera_{side}_optical_joint", "fixed", camera,
                                f"camera_{side}_optical", (0.0, 0.0, 0.0),
                                rpy=(-math.pi / 2, 0.0, -math.pi / 2)))
        links.append(LinkSpec(f"camera_{side}_optical", 0.0, (0.0, 0.0, 0.0)))
    return joints, links


def armar3b_description() -> tuple[list[JointSpec], list[LinkSpec]]:
    """All joints and links of ARMAR-IIIb (see the module docstring for the tree)."""
    deg45 = math.radians(45.0)
    joints = [
        JointSpec("platform_x", "prismatic", "world", "platform_x_link", (0.0, 0.0, 0.0),
                  (1.0, 0.0, 0.0), -10.0, 10.0, 2000.0, 1.0),
        JointSpec("platform_y", "prismatic", "platform_x_link", "platform_y_link",
                  (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), -10.0, 10.0, 2000.0, 1.0),
        JointSpec("platform_yaw", "revolute", "platform_y_link", "base_link", (0.0, 0.0, 0.0),
                  (0.0, 0.0, 1.0), -2 * math.pi, 2 * math.pi, 2000.0, 1.0),
        JointSpec("hip_pitch", "revolute", "base_link", "hip_pitch_link", (0.158, 0.0, 0.890),
                  (0.0, -1.0, 0.0), -deg45, deg45, 1000.0),
        JointSpec("hip_roll", "revolute", "hip_pitch_link", "hip_roll_link", (0.0, 0.0, 0.0),
                  (1.0, 0.0, 0.0), -deg45, deg45, 1000.0),
        JointSpec("hip_yaw", "revolute", "hip_roll_link", "torso", (0.0, 0.0, 0.0),
                  (0.0, 0.0, 1.0), -deg45, deg45, 1000.0),
    ]
    links = [
        LinkSpec("world", 0.0, (0.0, 0.0, 0.0)),
        LinkSpec("platform_x_link", 0.1, (0.0, 0.0, 0.0)),
        LinkSpec("platform_y_link", 0.1, (0.0, 0.0, 0.0)),
        LinkSpec("base_link", 100.0, (0.0, 0.0, 0.20),
                 (Box(PLATFORM_SIZE, (0.0, 0.0, PLATFORM_SIZE[2] / 2)),), "platform"),
        LinkSpec("hip_pitch_link", 10.0, (0.0, 0.0, 0.0)),
        LinkSpec("hip_roll_link", 10.0, (0.0, 0.0, 0.0)),
        # torso box spans z 0.911-1.522 m above the floor, i.e. 0.021-0.632 m above the hip
        LinkSpec("torso", 15.4, (-0.035, 0.0, 0.3265),
                 (Box((0.295, 0.361, 0.611), (-0.035, 0.0, 0.3265)),), "torso"),
    ]
    for part in (_arm("r"), _arm("l"), _head()):
        joints += part[0]
        links += part[1]
    return joints, links


# ----------------------------------------------------------------------------- URDF writing

_COLORS = {"grey": (0.6, 0.6, 0.6, 1.0), "platform": (0.25, 0.25, 0.3, 1.0),
           "torso": (0.85, 0.85, 0.85, 1.0), "arm": (0.75, 0.75, 0.78, 1.0),
           "hand": (0.35, 0.35, 0.35, 1.0), "head": (0.9, 0.9, 0.9, 1.0),
           "eye": (0.1, 0.1, 0.1, 1.0)}


#: Mass (kg) written for frame-only links (TCP, cameras).
_FRAME_LINK_MASS = 1e-5


def _fmt(values) -> str:
    return " ".join(f"{v:.6g}" if abs(v) > 1e-12 else "0" for v in values)


def _rpy_z_to(direction: np.ndarray) -> tuple[float, float, float]:
    """URDF rpy of a rotation taking +z onto ``direction`` (unit (3,))."""
    d = direction / np.linalg.norm(direction)
    pitch = math.atan2(math.hypot(d[0], d[1]), d[2])
    yaw = math.atan2(d[1], d[0])
    return (0.0, pitch, yaw)


def _shape_xml(shape) -> tuple[str, tuple, tuple]:
    """Geometry XML and its origin (xyz, rpy)."""
    if isinstance(shape, Box):
        return f'<box size="{_fmt(shape.size)}"/>', shape.xyz, shape.rpy
    if isinstance(shape, Sphere):
        return f'<sphere radius="{shape.radius:.6g}"/>', shape.xyz, (0.0, 0.0, 0.0)
    start, end = np.asarray(shape.start), np.asarray(shape.end)
    length = float(np.linalg.norm(end - start))
    centre = tuple(0.5 * (start + end))
    return (f'<cylinder radius="{shape.radius:.6g}" length="{length:.6g}"/>', centre,
            _rpy_z_to(end - start))


def _inertia(link: LinkSpec) -> tuple[float, float, float]:
    """Diagonal inertia (kg m^2) of a link: its mass spread over its first shape's bounding
    box (a point-like 5 cm cube when it has no shape)."""
    extent = np.full(3, 0.05)
    if link.shapes:
        shape = link.shapes[0]
        if isinstance(shape, Box):
            extent = np.asarray(shape.size)
        elif isinstance(shape, Sphere):
            extent = np.full(3, 2 * shape.radius)
        else:
            extent = np.abs(np.asarray(shape.end) - np.asarray(shape.start)) + 2 * shape.radius
    a, b, c = extent
    m = max(link.mass, _FRAME_LINK_MASS) / 12.0
    return m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b)


def _link_xml(link: LinkSpec) -> list[str]:
    lines = [f'  <link name="{link.name}">']
    if link.name != "world":
        # frame-only links get a negligible mass: PyBullet gives links without one 1 kg
        ixx, iyy, izz = _inertia(link)
        lines += ["    <inertial>",
                  f'      <origin xyz="{_fmt(link.com)}" rpy="0 0 0"/>',
                  f'      <mass value="{max(link.mass, _FRAME_LINK_MASS):.6g}"/>',
                  f'      <inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" '
                  f'izz="{izz:.6g}"/>',
                  "    </inertial>"]
    for shape in link.shapes:
        geometry, xyz, rpy = _shape_xml(shape)
        for tag in ("visual", "collision"):
            lines += [f"    <{tag}>", f'      <origin xyz="{_fmt(xyz)}" rpy="{_fmt(rpy)}"/>',
                      f"      <geometry>{geometry}</geometry>"]
            if tag == "visual":
                lines.append(f'      <material name="{link.color}"/>')
            lines.append(f"    </{tag}>")
    lines.append("  </link>")
    return lines


def _joint_xml(joint: JointSpec) -> list[str]:
    lines = [f'  <joint name="{joint.name}" type="{joint.kind}">',
             f'    <parent link="{joint.parent}"/>', f'    <child link="{joint.child}"/>',
             f'    <origin xyz="{_fmt(joint.xyz)}" rpy="{_fmt(joint.rpy)}"/>']
    if joint.kind != "fixed":
        lines += [f'    <axis xyz="{_fmt(joint.axis)}"/>',
                  f'    <limit lower="{joint.lower:.6g}" upper="{joint.upper:.6g}" '
                  f'effort="{joint.effort:.6g}" velocity="{joint.velocity:.6g}"/>']
    lines.append("  </joint>")
    return lines


def armar3b_urdf() -> str:
    """The URDF text of ARMAR-IIIb (the content of the shipped ``assets/armar3b.urdf``)."""
    joints, links = armar3b_description()
    lines = ['<?xml version="1.0"?>',
             "<!-- ARMAR-IIIb for wipelab, generated by wipelab.sim.armar3.armar3b_urdf().",
             "     Kinematics, limits and masses from KIT's Simox ARMAR-III model; hand mass,",
             "     head mass split and link shapes are estimates. Do not edit by hand. -->",
             f'<robot name="{ROBOT_NAME}">']
    for name, rgba in _COLORS.items():
        lines.append(f'  <material name="{name}"><color rgba="{_fmt(rgba)}"/></material>')
    for link in links:
        lines += _link_xml(link)
    for joint in joints:
        lines += _joint_xml(joint)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def armar3b_urdf_path() -> Path:
    """Path of the shipped URDF (package data)."""
    return Path(str(resources.files("wipelab.sim") / "assets" / "armar3b.urdf"))
