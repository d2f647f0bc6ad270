"""A URDF's visual geometry as solids per link, for viewers that do not read URDF.

Foxglove's 3D panel draws ``foxglove.SceneUpdate`` primitives but cannot read a URDF stored
in an MCAP; :func:`urdf_visuals` turns each link's ``<visual>`` boxes, cylinders and spheres
into (kind, pose in the link frame, size, colour), which
:meth:`wipelab.logs.StageRecorder.shapes` writes as frame-locked entities on the link
frames that ``/tf`` moves.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from wipelab.rotations import quaternion_xyzw_from_rotation, rotation_from_rpy

#: Colour of a visual without a material colour (RGBA, 0..1).
DEFAULT_RGBA = (0.7, 0.7, 0.7, 1.0)


def _floats(text: str | None, default: str) -> list[float]:
    return [float(v) for v in (text or default).split()]


def _size(geometry: ET.Element) -> tuple[str, list[float]] | None:
    """(kind, bounding-box size (3,) m along the shape's axes) of a URDF <geometry>."""
    box, cylinder, sphere = (geometry.find(tag) for tag in ("box", "cylinder", "sphere"))
    if box is not None:
        return "box", _floats(box.get("size"), "0 0 0")
    if cylinder is not None:  # URDF and Foxglove cylinders both lie along z
        diameter = 2.0 * float(cylinder.get("radius"))
        return "cylinder", [diameter, diameter, float(cylinder.get("length"))]
    if sphere is not None:
        return "sphere", [2.0 * float(sphere.get("radius"))] * 3
    return None  # meshes: not drawn


def urdf_visuals(urdf_text: str) -> dict[str, list[tuple]]:
    """Visual solids of every link: link name -> ``[(kind, translation (3,), q_xyzw (4,),
    size (3,), rgba (4,) uint8), ...]`` in the link's frame; kind "box", "cylinder" or
    "sphere" (meshes are left out). Links without visuals are not listed."""
    root = ET.fromstring(urdf_text)
    named = {m.get("name"): m.find("color") for m in root.findall("material")}
    out: dict[str, list[tuple]] = {}
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            geometry = visual.find("geometry")
            shape = None if geometry is None else _size(geometry)
            if shape is None:
                continue
            origin = visual.find("origin")
            xyz = _floats(None if origin is None else origin.get("xyz"), "0 0 0")
            rpy = _floats(None if origin is None else origin.get("rpy"), "0 0 0")
            material = visual.find("material")
            colour = None if material is None else material.find("color")
            if colour is None and material is not None:
                colour = named.get(material.get("name"))
            rgba = DEFAULT_RGBA if colour is None else _floats(colour.get("rgba"), "0.7 0.7 0.7 1")
            out.setdefault(link.get("name"), []).append(
                (shape[0], np.array(xyz), quaternion_xyzw_from_rotation(rotation_from_rpy(rpy)),
                 np.array(shape[1]), np.round(np.clip(rgba, 0, 1) * 255).astype(np.uint8)))
    return out
