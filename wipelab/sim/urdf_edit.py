"""Edits of a URDF document for simulation: hold joints fixed, keep a subtree, attach a
compliant tool.

Pure XML (``xml.etree``); the shipped URDF stays as it is and the simulator loads an edited
copy. Holding the joints a task does not use as ``fixed`` and leaving out the links that
cannot move makes PyBullet's multibody several times cheaper to step (no motors, no limits,
fewer links to propagate).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from wipelab.rotations import rpy_from_rotation
from wipelab.sim.kinematics import parse_urdf_joints


def _fmt(values) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def freeze_joints(urdf_text: str, keep, values: dict[str, float] | None = None) -> str:
    """Turn every movable joint not in ``keep`` into a fixed joint at its value in ``values``
    (rad or m; 0 if absent), baking the motion into the joint's origin."""
    keep = set(keep)
    values = dict(values or {})
    joints = parse_urdf_joints(urdf_text)
    root = ET.fromstring(urdf_text)
    for element in root.iter("joint"):
        name = element.get("name")
        if name in keep or element.get("type") == "fixed":
            continue
        pose = joints[name].transform(float(values.get(name, 0.0)))
        element.set("type", "fixed")
        origin = element.find("origin")
        if origin is None:
            origin = ET.SubElement(element, "origin")
        origin.set("xyz", _fmt(pose[:3, 3]))
        origin.set("rpy", _fmt(rpy_from_rotation(pose[:3, :3])))
        for tag in ("axis", "limit", "dynamics"):
            child = element.find(tag)
            if child is not None:
                element.remove(child)
    return ET.tostring(root, encoding="unicode")


def drop_subtrees(urdf_text: str, joints) -> str:
    """Remove the named joints and everything below them (links and joints)."""
    root = ET.fromstring(urdf_text)
    children: dict[str, list] = {}
    for element in root.findall("joint"):
        children.setdefault(element.find("parent").get("link"), []).append(element)
    by_name = {element.get("name"): element for element in root.findall("joint")}
    dropped_joints, dropped_links = set(), set()
    stack = [by_name[name] for name in joints]
    while stack:
        element = stack.pop()
        child = element.find("child").get("link")
        dropped_joints.add(element.get("name"))
        dropped_links.add(child)
        stack += children.get(child, [])
    for element in list(root):
        if ((element.tag == "joint" and element.get("name") in dropped_joints)
                or (element.tag == "link" and element.get("name") in dropped_links)):
            root.remove(element)
    return ET.tostring(root, encoding="unicode")


def subtree(urdf_text: str, root_link: str) -> str:
    """Keep ``root_link`` and everything below it; it becomes the document's root link."""
    root = ET.fromstring(urdf_text)
    children: dict[str, list[str]] = {}
    for element in root.findall("joint"):
        children.setdefault(element.find("parent").get("link"), []).append(
            element.find("child").get("link"))
    kept, stack = set(), [root_link]
    while stack:
        link = stack.pop()
        kept.add(link)
        stack += children.get(link, [])
    for element in list(root):
        if ((element.tag == "link" and element.get("name") not in kept)
                or (element.tag == "joint" and element.find("parent").get("link") not in kept)):
            root.remove(element)
    return ET.tostring(root, encoding="unicode")


def attach_compliant_box(urdf_text: str, parent_link: str, mount: np.ndarray, name: str,
                         size, mass: float, max_compression: float, spheres: np.ndarray,
                         sphere_radius: float, rgba=(0.95, 0.8, 0.1, 1.0)) -> str:
    """Attach a box tool on a prismatic joint along its own z axis.

    ``<name>_compression`` (prismatic from ``parent_link``, origin ``mount`` (4, 4): the tool
    frame at rest in ``parent_link``'s frame; along +z of the tool frame, 0 at rest, positive
    = compressed toward the parent, up to ``max_compression`` m) -> ``<name>`` (the box of
    ``size`` (3,) m and ``mass`` kg, centred on the tool frame; its collision shape is the
    spheres of ``sphere_radius`` (m) at ``spheres`` (k, 3)). The simulator makes the
    prismatic joint a spring.
    """
    root = ET.fromstring(urdf_text)
    sx, sy, sz = size
    inertia = mass / 12.0 * np.array([sy * sy + sz * sz, sx * sx + sz * sz, sx * sx + sy * sy])
    tool = ET.SubElement(root, "link", name=name)
    inertial = ET.SubElement(tool, "inertial")
    ET.SubElement(inertial, "mass", value=f"{mass:.9g}")
    ET.SubElement(inertial, "inertia", ixx=f"{inertia[0]:.9g}", ixy="0", ixz="0",
                  iyy=f"{inertia[1]:.9g}", iyz="0", izz=f"{inertia[2]:.9g}")
    visual = ET.SubElement(tool, "visual")
    ET.SubElement(visual, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(ET.SubElement(visual, "geometry"), "box", size=_fmt(size))
    ET.SubElement(ET.SubElement(visual, "material", name=f"{name}_color"), "color", rgba=_fmt(rgba))
    for centre in spheres:
        collision = ET.SubElement(tool, "collision")
        ET.SubElement(collision, "origin", xyz=_fmt(centre), rpy="0 0 0")
        ET.SubElement(ET.SubElement(collision, "geometry"), "sphere", radius=f"{sphere_radius:.9g}")
    slide = ET.SubElement(root, "joint", name=f"{name}_compression", type="prismatic")
    ET.SubElement(slide, "parent", link=parent_link)
    ET.SubElement(slide, "child", link=name)
    ET.SubElement(slide, "origin", xyz=_fmt(mount[:3, 3]),
                  rpy=_fmt(rpy_from_rotation(mount[:3, :3])))
    ET.SubElement(slide, "axis", xyz="0 0 1")
    ET.SubElement(slide, "limit", lower=f"{-0.1 * max_compression:.9g}",
                  upper=f"{max_compression:.9g}", effort="1000", velocity="10")
    return ET.tostring(root, encoding="unicode")
