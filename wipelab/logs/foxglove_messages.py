"""Foxglove well-known messages (protobuf) built from numpy arrays.

Pure functions: arrays in, ``foxglove.messages`` objects out. ``Message.encode()`` gives the
protobuf bytes and ``Message.get_schema()`` the ``foxglove.*`` schema (a FileDescriptorSet),
which :mod:`wipelab.logs.mcap_log` writes under the schema's exact name so that Foxglove and
``rerun mcap convert`` recognise it. Quaternions are (x, y, z, w) throughout.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from foxglove import messages as fm

_IMAGE_MAGIC = ((b"\xff\xd8\xff", "jpeg"), (b"\x89PNG\r\n\x1a\n", "png"))


def timestamp(ns: int) -> fm.Timestamp:
    """Data time in nanoseconds -> ``foxglove.Timestamp`` {sec, nsec}."""
    sec, nsec = divmod(int(ns), 1_000_000_000)
    return fm.Timestamp(sec, nsec)


def vector3(v: np.ndarray) -> fm.Vector3:
    x, y, z = (float(c) for c in np.asarray(v, dtype=float).reshape(3))
    return fm.Vector3(x=x, y=y, z=z)


def unit_quaternion(q_xyzw) -> np.ndarray:
    """Quaternion (x, y, z, w) (4,) scaled to unit norm; a zero or non-finite one is rejected."""
    return unit_quaternions(np.asarray(q_xyzw, dtype=float).reshape(1, 4))[0]


def unit_quaternions(q_xyzw) -> np.ndarray:
    """Quaternions (x, y, z, w) (n, 4) scaled to unit norm; a zero or non-finite one is rejected."""
    q = np.asarray(q_xyzw, dtype=float).reshape(-1, 4)
    norms = np.sqrt(np.einsum("ij,ij->i", q, q))
    bad = ~(np.isfinite(norms) & (norms > 0.0))
    if bad.any():
        raise ValueError(f"quaternion (x, y, z, w) must be finite and non-zero, got "
                         f"{q[np.flatnonzero(bad)[0]].tolist()}")
    return q / norms[:, None]


def quaternion(q_xyzw) -> fm.Quaternion:
    """``foxglove.Quaternion`` of ``unit_quaternion(q_xyzw)``."""
    x, y, z, w = unit_quaternion(q_xyzw).tolist()
    return fm.Quaternion(x=x, y=y, z=z, w=w)


def pose(translation: np.ndarray, q_xyzw: np.ndarray) -> fm.Pose:
    return fm.Pose(position=vector3(translation), orientation=quaternion(q_xyzw))


def _rows(translations, q_xyzw) -> tuple[list, list]:
    """Translations (n, 3) and unit quaternions (n, 4) as lists of float rows (normalised in
    one call: the same values as :func:`unit_quaternion` row by row)."""
    return (np.asarray(translations, dtype=float).reshape(-1, 3).tolist(),
            unit_quaternions(q_xyzw).tolist())


def rgba_uint8(colors, n: int) -> np.ndarray:
    """Colours -> (n, 4) uint8 RGBA.

    ``colors`` is one colour (3,) / (4,) or one per item (n, 3) / (n, 4); integer arrays are
    0..255, float arrays 0..1.
    """
    c = np.asarray(colors)
    if c.ndim == 1:
        c = np.broadcast_to(c, (n, c.shape[0]))
    if c.shape[0] != n or c.shape[1] not in (3, 4):
        raise ValueError(f"colors must have shape (3,), (4,), ({n}, 3) or ({n}, 4), got {np.shape(colors)}")
    c = np.round(np.clip(c, 0.0, 1.0) * 255.0) if np.issubdtype(c.dtype, np.floating) else np.clip(c, 0, 255)
    c = c.astype(np.uint8)
    if c.shape[1] == 3:
        c = np.concatenate([c, np.full((n, 1), 255, np.uint8)], axis=1)
    return np.ascontiguousarray(c)


def color(rgba: np.ndarray) -> fm.Color:
    """(4,) uint8 RGBA -> ``foxglove.Color`` (floats 0..1)."""
    r, g, b, a = (float(c) / 255.0 for c in rgba)
    return fm.Color(r=r, g=g, b=b, a=a)


def image_format(data: bytes) -> str:
    """Foxglove ``format`` of an encoded image from its magic bytes ("jpeg", "png", "webp")."""
    for magic, name in _IMAGE_MAGIC:
        if data.startswith(magic):
            return name
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        return "webp"
    raise ValueError("image data is neither JPEG, PNG nor WebP (unknown magic bytes)")


def frame_transforms(ns: int, transforms) -> fm.FrameTransforms:
    """``foxglove.FrameTransforms`` from ``[(parent, child, translation (3,), q_xyzw (4,)), ...]``."""
    return next(frame_transforms_series([ns], transforms))


def frame_transforms_series(ns: list[int], frames) -> Iterator[fm.FrameTransforms]:
    """:func:`frame_transforms` at each time ``ns[k]`` from moving frames ``[(parent, child,
    translations (n, 3), q_xyzw (n, 4)), ...]`` (each frame's arrays converted once)."""
    frames = [(parent, child, *_rows(t, q)) for parent, child, t, q in frames]
    for k, time_ns in enumerate(ns):
        stamp = timestamp(time_ns)
        yield fm.FrameTransforms(transforms=[
            fm.FrameTransform(timestamp=stamp, parent_frame_id=parent, child_frame_id=child,
                              translation=fm.Vector3(x=t[k][0], y=t[k][1], z=t[k][2]),
                              rotation=fm.Quaternion(x=q[k][0], y=q[k][1], z=q[k][2],
                                                     w=q[k][3]))
            for parent, child, t, q in frames])


def pose_in_frame(ns: int, frame_id: str, translation, q_xyzw) -> fm.PoseInFrame:
    return next(poses_in_frame([ns], frame_id, translation, q_xyzw))


def poses_in_frame(ns: list[int], frame_id: str, translations, q_xyzw
                   ) -> Iterator[fm.PoseInFrame]:
    """:func:`pose_in_frame` at each time ``ns[k]`` for poses (n, 3) and (n, 4)."""
    for time_ns, (x, y, z), (qx, qy, qz, qw) in zip(ns, *_rows(translations, q_xyzw)):
        yield fm.PoseInFrame(timestamp=timestamp(time_ns), frame_id=frame_id, pose=fm.Pose(
            position=fm.Vector3(x=x, y=y, z=z), orientation=fm.Quaternion(x=qx, y=qy, z=qz,
                                                                          w=qw)))


def camera_calibration(ns: int, K: np.ndarray, D: np.ndarray, width: int, height: int,
                       frame_id: str, R: np.ndarray | None = None,
                       P: np.ndarray | None = None) -> fm.CameraCalibration:
    """``foxglove.CameraCalibration`` with the OpenCV ``plumb_bob`` model (ROS CameraInfo).

    K (3, 3) intrinsics in pixels; D (5,) (k1, k2, p1, p2, k3); R (3, 3) rectification
    rotation (identity if None); P (3, 4) projection (``[K | 0]`` if None).
    """
    K = np.asarray(K, dtype=float).reshape(3, 3)
    D = np.asarray(D, dtype=float).reshape(-1)
    R = np.eye(3) if R is None else np.asarray(R, dtype=float).reshape(3, 3)
    P = np.hstack([K, np.zeros((3, 1))]) if P is None else np.asarray(P, dtype=float).reshape(3, 4)
    return fm.CameraCalibration(
        timestamp=timestamp(ns), frame_id=frame_id, width=int(width), height=int(height),
        distortion_model="plumb_bob" if D.size in (4, 5) else "rational_polynomial",
        D=D.tolist(), K=K.ravel().tolist(), R=R.ravel().tolist(), P=P.ravel().tolist())


def compressed_image(ns: int, data: bytes, frame_id: str, image_format_name: str) -> fm.CompressedImage:
    return fm.CompressedImage(timestamp=timestamp(ns), frame_id=frame_id, data=bytes(data),
                              format=image_format_name)


def compressed_video(ns: int, data: bytes, frame_id: str, codec: str) -> fm.CompressedVideo:
    """One access unit of an H.264/H.265 Annex B stream ("h264", "h265") or AV1 OBUs ("av1")."""
    return fm.CompressedVideo(timestamp=timestamp(ns), frame_id=frame_id, data=bytes(data), format=codec)


#: Layout of ``point_cloud``: x, y, z float32 then packed RGBA uint32 (bytes r, g, b, a).
POINT_CLOUD_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgba", "u1", (4,))])


def point_cloud(ns: int, frame_id: str, points: np.ndarray, rgba: np.ndarray) -> fm.PointCloud:
    """``foxglove.PointCloud`` of points (n, 3) in metres (stored as float32) with colours (n, 4) uint8."""
    packed = np.empty(points.shape[0], POINT_CLOUD_DTYPE)
    packed["x"], packed["y"], packed["z"] = points[:, 0], points[:, 1], points[:, 2]
    packed["rgba"] = rgba
    f32, u32 = fm.PackedElementFieldNumericType.Float32, fm.PackedElementFieldNumericType.Uint32
    fields = [fm.PackedElementField(name="x", offset=0, type=f32),
              fm.PackedElementField(name="y", offset=4, type=f32),
              fm.PackedElementField(name="z", offset=8, type=f32),
              fm.PackedElementField(name="rgba", offset=12, type=u32)]
    identity = pose(np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))
    return fm.PointCloud(timestamp=timestamp(ns), frame_id=frame_id, pose=identity,
                         point_stride=POINT_CLOUD_DTYPE.itemsize, fields=fields, data=packed.tobytes())


def _scene_update(ns: int, frame_id: str, entity_id: str, **primitives) -> fm.SceneUpdate:
    entity = fm.SceneEntity(timestamp=timestamp(ns), frame_id=frame_id, id=entity_id, **primitives)
    return fm.SceneUpdate(entities=[entity])


#: Kinds of solid: their Foxglove primitive and the ``SceneEntity`` field that lists them.
SHAPE_PRIMITIVES = {"box": (fm.CubePrimitive, "cubes"),
                    "cylinder": (fm.CylinderPrimitive, "cylinders"),
                    "sphere": (fm.SpherePrimitive, "spheres")}


def shape_primitive(kind: str, translation, q_xyzw, size, rgba):
    """A ``foxglove.CubePrimitive`` / ``CylinderPrimitive`` / ``SpherePrimitive``.

    ``kind`` is "box", "cylinder" (axis along its z) or "sphere"; ``size`` (3,) the extent
    of its bounding box along its own axes (m), ``translation`` (3,) and ``q_xyzw`` (4,) its
    pose in the entity's frame, ``rgba`` (4,) uint8.
    """
    primitive, _ = SHAPE_PRIMITIVES[kind]
    return primitive(pose=pose(translation, q_xyzw), size=vector3(size), color=color(rgba))


def scene_shapes(ns: int, entities) -> fm.SceneUpdate:
    """A ``foxglove.SceneUpdate`` of solids: ``entities`` is ``[(entity id, frame_id,
    [(kind, translation, q_xyzw, size, rgba), ...]), ...]`` (see :func:`shape_primitive`).

    The entities are frame-locked: they move with their frame as /tf moves it.
    """
    stamp, out = timestamp(ns), []
    for entity_id, frame_id, shapes in entities:
        primitives = {group: [] for _, group in SHAPE_PRIMITIVES.values()}
        for kind, translation, q_xyzw, size, rgba in shapes:
            primitives[SHAPE_PRIMITIVES[kind][1]].append(shape_primitive(kind, translation, q_xyzw, size, rgba))
        out.append(fm.SceneEntity(timestamp=stamp, frame_id=frame_id, id=entity_id,
                                  frame_locked=True, **primitives))
    return fm.SceneUpdate(entities=out)


def scene_deletion(ns: int, entity_id: str) -> fm.SceneUpdate:
    """A ``foxglove.SceneUpdate`` that removes the entity ``entity_id`` (e.g. a lost sponge)."""
    return fm.SceneUpdate(deletions=[fm.SceneEntityDeletion(
        timestamp=timestamp(ns), type=fm.SceneEntityDeletionType.MatchingId, id=entity_id)])


#: ``foxglove.Log`` levels by name.
LOG_LEVELS = {"debug": fm.LogLevel.Debug, "info": fm.LogLevel.Info,
              "warning": fm.LogLevel.Warning, "error": fm.LogLevel.Error}


def log_message(ns: int, level: str, text: str, name: str) -> fm.Log:
    """A ``foxglove.Log`` (Foxglove's Log panel): ``level`` one of :data:`LOG_LEVELS`,
    ``name`` the emitting stage."""
    return fm.Log(timestamp=timestamp(ns), level=LOG_LEVELS[level], message=text, name=name,
                  file="", line=0)


def _rows_of(values: np.ndarray, width: int) -> list[list[float]]:
    """Rows of ``width`` Python floats of an array (..., width): what message fields take
    (several times faster than converting numpy scalars one by one)."""
    return np.reshape(np.asarray(values, dtype=float), (-1, width)).tolist()


def image_annotations(ns: int, lines: np.ndarray, line_rgba: np.ndarray, points: np.ndarray,
                      point_rgba: np.ndarray, thickness: float) -> fm.ImageAnnotations:
    """A ``foxglove.ImageAnnotations``: line segments (m, 2, 2) and points (k, 2) in pixels
    (origin at the top-left corner of the top-left pixel), colours (4,) uint8."""
    annotations = []
    stamp = timestamp(ns)
    if len(lines):
        annotations.append(fm.PointsAnnotation(
            timestamp=stamp, type=fm.PointsAnnotationType.LineList,
            points=[fm.Point2(x=x, y=y) for x, y in _rows_of(lines, 2)],
            outline_color=color(line_rgba), thickness=float(thickness)))
    if len(points):
        annotations.append(fm.PointsAnnotation(
            timestamp=stamp, type=fm.PointsAnnotationType.Points,
            points=[fm.Point2(x=x, y=y) for x, y in _rows_of(points, 2)],
            outline_color=color(point_rgba), fill_color=color(point_rgba), thickness=3.0))
    return fm.ImageAnnotations(points=annotations)


def scene_line_strip(ns: int, frame_id: str, entity_id: str, points: np.ndarray,
                     rgba: np.ndarray, thickness: float) -> fm.SceneUpdate:
    """A ``foxglove.SceneUpdate`` with one LINE_STRIP through points (n, 3), metres."""
    line = fm.LinePrimitive(
        type=fm.LinePrimitiveLineType.LineStrip, pose=pose(np.zeros(3), [0.0, 0.0, 0.0, 1.0]),
        thickness=float(thickness), scale_invariant=False,
        points=[fm.Point3(x=x, y=y, z=z) for x, y, z in _rows_of(points, 3)],
        color=color(rgba))
    return _scene_update(ns, frame_id, entity_id, lines=[line])


def rotation_x_to(vector: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) (4,) rotating +x onto the direction of ``vector`` (3,)."""
    v = np.asarray(vector, dtype=float)
    n = np.linalg.norm(v)
    if n == 0.0:
        return np.array([0.0, 0.0, 0.0, 1.0])
    u = v / n
    # Half-way quaternion between +x and u: q = (x × u, 1 + x·u), normalised.
    q = np.array([0.0, -u[2], u[1], 1.0 + u[0]])
    if q[3] < 1e-12:  # u == -x: rotate half a turn about z
        return np.array([0.0, 0.0, 1.0, 0.0])
    return q / np.linalg.norm(q)


#: Arrow head length as a fraction of the whole arrow (the rest is the shaft).
ARROW_HEAD_FRACTION = 0.2


def scene_arrows(ns: int, frame_id: str, entity_id: str, origins: np.ndarray, vectors: np.ndarray,
                 rgba: np.ndarray) -> fm.SceneUpdate:
    """A ``foxglove.SceneUpdate`` with one arrow per origin (n, 3) and vector (n, 3).

    An ArrowPrimitive points along +x of its pose; its total length (shaft + head) is |vector|.
    """
    arrows = []
    for origin, vector, c in zip(origins, vectors, rgba):
        length = float(np.linalg.norm(vector))
        head = ARROW_HEAD_FRACTION * length
        arrows.append(fm.ArrowPrimitive(
            pose=pose(origin, rotation_x_to(vector)), shaft_length=length - head,
            shaft_diameter=0.1 * length, head_length=head, head_diameter=0.2 * length,
            color=color(c)))
    return _scene_update(ns, frame_id, entity_id, arrows=arrows)
