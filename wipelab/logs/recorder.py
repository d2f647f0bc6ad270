"""``StageRecorder``: one MCAP file and one Rerun recording per stage run, side by side."""

from __future__ import annotations

import json
import math
import os
import re
import uuid
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from foxglove import messages as fm

from wipelab.logs import foxglove_messages as fx
from wipelab.logs.mcap_log import McapLog, json_bytes, json_ready
from wipelab.logs.phase_chart import PhaseChart
from wipelab.logs.rrd_file import capture_stream, deterministic_blueprint, write_canonical_rrd
from wipelab.logs.timebase import seconds_array_to_ns, seconds_to_ns
from wipelab.logs.video import access_units
from wipelab.manifest import sha256_file

#: Rerun application ids are ``wipelab_<stage>``: the viewer keeps one layout per application
#: id, so each stage's recording opens with its own layout even beside the others.
APPLICATION_ID_PREFIX = "wipelab_"
#: The data-time timeline (duration, seconds since the start of the recording).
TIMELINE = "time"
#: MCAP topic of all frame transforms; Rerun puts frame ``child`` on entity ``/tf/<child>``.
TF_TOPIC = "/tf"
#: The world frame (REP-103: x forward, y left, z up).
WORLD_FRAME = "world"
#: Rerun's frame of the root entity "/"; the world frame maps to it.
RERUN_ROOT_FRAME = "tf#/"
#: Suffix of the frame of a camera's image plane (as ``rerun mcap convert`` names it).
IMAGE_PLANE_SUFFIX = "_image_plane"
#: MCAP metadata record names.
METADATA_STAGE, METADATA_PARAMETERS, METADATA_INPUTS = "wipelab.stage", "wipelab.parameters", "wipelab.inputs"
#: Length of the axes drawn at a logged pose in Rerun (m).
POSE_AXIS_LENGTH = 0.1

_RECORDING_NAMESPACE = uuid.UUID("5f0c2a43-9a55-4c39-8d43-2b0f4ab1c7e2")
_SCALARS_SCHEMA = "wipelab.Scalars"
_STATE_SCHEMA = "wipelab.State"
#: Names a Foxglove message path can address (``/topic.name``): letters, digits, underscores.
PLOTTABLE_NAME = re.compile(r"[A-Za-z0-9_]+")


def _checked_topic(topic: str) -> str:
    if not topic.startswith("/") or topic.endswith("/") or "//" in topic:
        raise ValueError(f"topic {topic!r} must look like /a/b (leading '/', no empty parts)")
    return topic


def application_id(stage: str) -> str:
    """Rerun application id of a stage's recordings (``wipelab_<stage>``)."""
    return APPLICATION_ID_PREFIX + stage


def rerun_frame(frame_id: str) -> str:
    """Rerun transform-frame name of an MCAP ``frame_id`` (``world`` is Rerun's root frame)."""
    return RERUN_ROOT_FRAME if frame_id == WORLD_FRAME else frame_id


def recording_id(stage: str, parameters: dict[str, Any], input_hashes: dict[str, str]) -> str:
    """Deterministic Rerun recording id: uuid5 of stage, parameters and input hashes."""
    key = json_bytes({"stage": stage, "parameters": parameters, "inputs": input_hashes}).decode()
    return str(uuid.uuid5(_RECORDING_NAMESPACE, key))


def stage_panels() -> list:
    """Panel states of every stage layout: the left panel open (it lists the recordings, one
    per stage, when several are open), the selection panel hidden, the time panel as a bar."""
    return [rrb.BlueprintPanel(state="expanded"), rrb.SelectionPanel(state="hidden"),
            rrb.TimePanel(state="collapsed")]


def whole_run() -> rrb.TimeAxis:
    """A time axis over the whole recording, for time series and state timelines (not a
    window around the time cursor)."""
    return rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
                                                 end=rrb.TimeRangeBoundary.infinite()))


def default_blueprint() -> rrb.Blueprint:
    """Layout for a stage that brings none: the 3D scene beside all time series."""
    return rrb.Blueprint(rrb.Horizontal(rrb.Spatial3DView(origin="/", name="scene"),
                                        rrb.TimeSeriesView(origin="/", name="series")),
                         *stage_panels())


class StageRecorder:
    """Logs one stage run to ``<directory>/<stage>.mcap`` and ``<directory>/<stage>.rrd``.

    Use as a context manager; both files are complete when the ``with`` block ends, also
    when it raises. Times ``t`` are data time in seconds since the start of the recording
    (``>= 0``); MCAP ``log_time`` (and ``publish_time``) is the same clock in nanoseconds,
    Rerun logs it on the duration timeline ``"time"``. Each MCAP topic is also the Rerun
    entity path (see :mod:`wipelab.logs` for the naming scheme).

    Parameters
    ----------
    directory : existing directory to write into.
    stage : stage name, also the file stem; the Rerun application id is ``wipelab_<stage>``.
    parameters : the stage's parameters (JSON-serialisable); MCAP metadata
        ``wipelab.parameters`` (one key per parameter, JSON-encoded value).
    inputs : role -> input file; MCAP metadata ``wipelab.inputs`` holds ``<role>.sha256`` and
        ``<role>.file`` (base name). Parameters and input hashes make the recording id.
    blueprint : the stage's default Rerun layout; :func:`default_blueprint` if None.
    attachments : name -> file attached to the MCAP (calibration files, configs).
    sinks : Rerun sinks the recording streams to as well (a viewer watching it live, see
        :func:`~wipelab.logs.rrd_file.capture_stream`); the ``.rrd`` file is the same.

    Attributes
    ----------
    rerun : rerun.RecordingStream
        For anything the methods do not cover. Set the time yourself before each such
        record (``rec.rerun.set_time("time", duration=t)``): the methods below may move it.
    mcap_path, rrd_path : pathlib.Path
    recording_id : str
    input_hashes : dict of str
        role -> sha256 of each input file.
    """

    def __init__(self, directory: str | os.PathLike, stage: str,
                 parameters: dict[str, Any] | None = None,
                 inputs: dict[str, str | os.PathLike] | None = None,
                 blueprint: rrb.BlueprintLike | None = None,
                 attachments: dict[str, str | os.PathLike] | None = None, sinks=()):
        directory = Path(directory)
        self.stage = stage
        self.application_id = application_id(stage)
        self.mcap_path = directory / f"{stage}.mcap"
        self.rrd_path = directory / f"{stage}.rrd"
        self._rrd_part = directory / f"{stage}.rrd.part"
        self.parameters = json_ready(dict(parameters or {}))
        input_paths = {role: Path(p) for role, p in sorted((inputs or {}).items())}
        self.input_hashes = {role: sha256_file(p) for role, p in input_paths.items()}
        self.recording_id = recording_id(stage, self.parameters, self.input_hashes)
        self._closed = False
        self._video_streams: set[str] = set()
        self._placed: set[tuple[str, str]] = set()   # (entity, frame) logged statically

        described_inputs = {}
        for role, p in input_paths.items():
            described_inputs[f"{role}.sha256"] = self.input_hashes[role]
            described_inputs[f"{role}.file"] = p.name
        attached = {name: Path(p).read_bytes() for name, p in sorted((attachments or {}).items())}

        layout = deterministic_blueprint(blueprint or default_blueprint(), self.recording_id)
        self._mcap_file = open(self.mcap_path, "wb")  # an unusable directory raises an OSError here
        try:
            self.rerun = capture_stream(self.application_id, self.recording_id, self._rrd_part,
                                        layout, sinks)
        except BaseException:
            self._mcap_file.close()
            self.mcap_path.unlink()
            raise
        self.rerun.send_recording_name(stage)  # what the viewer lists it as
        self._mcap = McapLog(self._mcap_file)
        self._mcap.metadata(METADATA_STAGE, {"stage": stage, "recording_id": self.recording_id})
        self._mcap.metadata(METADATA_PARAMETERS,
                            {k: json_bytes(v).decode() for k, v in self.parameters.items()})
        self._mcap.metadata(METADATA_INPUTS, described_inputs)
        for name, data in attached.items():
            self.attach(name, data)

    # -- lifetime --------------------------------------------------------------------------
    def __enter__(self) -> "StageRecorder":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def close(self) -> None:
        """Finish the MCAP file and write the reproducible ``.rrd`` (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._mcap.finish()
        finally:
            self._mcap_file.close()
            self.rerun.flush()
            self.rerun.disconnect()
        try:
            write_canonical_rrd(self._rrd_part, self.rrd_path, self.application_id,
                                self.recording_id)
        finally:
            self._rrd_part.unlink(missing_ok=True)

    # -- helpers ---------------------------------------------------------------------------
    def _at(self, t: float) -> int:
        """Data time ``t`` (s) -> ns; also the Rerun stream's current time."""
        ns = seconds_to_ns(t)
        self.rerun.set_time(TIMELINE, duration=np.timedelta64(ns, "ns"))
        return ns

    def _write(self, topic: str, ns: int, message) -> None:
        self._mcap.write(self._mcap.protobuf_channel(topic, type(message)), ns, message.encode())

    def _place(self, entity: str, frame_id: str) -> None:
        """Put a Rerun entity into the named frame ``frame_id`` (world: the root, nothing to do);
        static, so once per entity and frame."""
        if frame_id != WORLD_FRAME and (entity, frame_id) not in self._placed:
            self._placed.add((entity, frame_id))
            self.rerun.log(entity, rr.CoordinateFrame(frame_id), static=True)

    # -- public logging API ----------------------------------------------------------------
    def scalars(self, topic: str, t: np.ndarray, values: np.ndarray,
                names: Sequence[str] | None = None, colors=None) -> None:
        """A time series: ``values`` (n, k) or (n,) at times ``t`` (n,) in seconds.

        MCAP: JSON channel, schema ``wipelab.Scalars``, one message ``{name: value, ...}``
        per time stamp (non-finite values as null), so that Foxglove plots ``/topic.name``.
        Rerun: ``Scalars`` via ``send_columns``, series named (and coloured) by a static
        ``SeriesLines``; a non-finite value leaves a gap in the line. ``names`` (letters,
        digits and ``_`` only: what a Foxglove message path can address) default to
        ``value`` for one column, ``value_0``, ``value_1``, ... otherwise; ``colors`` (k, 3)
        uint8, one per series (the viewer picks if None).
        """
        entity = _checked_topic(topic)
        ns = seconds_array_to_ns(t)
        values = np.asarray(values, dtype=float)
        if values.ndim == 1:
            values = values[:, None]
        if values.ndim != 2 or values.shape[0] != ns.size:
            raise ValueError(f"{topic}: values must have shape ({ns.size}, k) or ({ns.size},), "
                             f"got {values.shape}")
        k = values.shape[1]
        names = ["value"] if names is None and k == 1 else \
            [f"value_{i}" for i in range(k)] if names is None else [str(n) for n in names]
        if len(names) != k or len(set(names)) != k:
            raise ValueError(f"{topic}: need {k} distinct names, got {names}")
        unplottable = [n for n in names if not PLOTTABLE_NAME.fullmatch(n)]
        if unplottable:
            raise ValueError(f"{topic}: series names may hold only letters, digits and '_' "
                             f"(Foxglove message paths), got {unplottable}")
        schema = {"title": _SCALARS_SCHEMA, "type": "object",
                  "properties": {n: {"type": ["number", "null"]} for n in names},
                  "required": sorted(names)}
        channel = self._mcap.json_channel(topic, _SCALARS_SCHEMA, schema)
        # Canonical JSON (sorted keys, no spaces) by string formatting: %r of a finite float
        # is exactly what json.dumps writes, and this is several times faster per row.
        order = sorted(range(k), key=lambda i: names[i])
        keys = [json.dumps(names[i], ensure_ascii=False) for i in order]
        template = "{" + ",".join(f"{key}:%r" for key in keys) + "}"
        columns = values[:, order]
        finite_rows = np.isfinite(columns).all(axis=1).tolist()
        write = self._mcap.write
        for time_ns, row, finite in zip(ns.tolist(), columns.tolist(), finite_rows):
            text = template % tuple(row) if finite else \
                "{" + ",".join(f"{key}:{v!r}" if math.isfinite(v) else f"{key}:null"
                               for key, v in zip(keys, row)) + "}"
            write(channel, time_ns, text.encode())
        style = rr.SeriesLines(names=names) if colors is None else \
            rr.SeriesLines(names=names, colors=fx.rgba_uint8(colors, k))
        self.rerun.log(entity, style, static=True)
        self.rerun.send_columns(entity, indexes=[rr.TimeColumn(TIMELINE, duration=ns.astype("timedelta64[ns]"))],
                                columns=rr.Scalars.columns(scalars=values))

    def points3d(self, topic: str, t: float, points: np.ndarray, colors=None, radii=None,
                 frame_id: str = WORLD_FRAME) -> None:
        """Points (n, 3) in metres in ``frame_id`` at time ``t``: :meth:`points3d_series` at
        one time (``colors`` one or (n, 3|4); ``radii`` scalar or (n,))."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        self.points3d_series(topic, [t], points, [points.shape[0]], colors, radii, frame_id)

    def points3d_series(self, topic: str, t: np.ndarray, points: np.ndarray, counts,
                        colors=None, radii=None, frame_id: str = WORLD_FRAME) -> None:
        """Points in metres in ``frame_id`` at times ``t`` (n,): the next ``counts[k]`` rows of
        ``points`` (sum(counts), 3) at ``t[k]``.

        MCAP: one ``foxglove.PointCloud`` (x, y, z float32 + rgba) per time. Rerun:
        ``Points3D`` (one ``send_columns``). ``colors``: one colour (3,)/(4,) or one per point
        (sum(counts), 3|4), uint8 0..255 or float 0..1 (white if None); ``radii``: metres, a
        scalar (one for each time) or one per point (Rerun only: Foxglove sizes points in
        the panel).
        """
        entity = _checked_topic(topic)
        ns, index = self._time_column(t)
        if not ns.size:
            return
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        counts = np.asarray(counts, dtype=np.int64).reshape(-1)
        if counts.size != ns.size or counts.sum() != points.shape[0]:
            raise ValueError(f"{topic}: need {ns.size} counts adding up to the "
                             f"{points.shape[0]} points")
        rgba = fx.rgba_uint8((255, 255, 255) if colors is None else colors, points.shape[0])
        ends = np.cumsum(counts).tolist()
        channel = self._mcap.protobuf_channel(topic, fm.PointCloud)
        for time_ns, start, end in zip(ns.tolist(), [0, *ends[:-1]], ends):
            self._mcap.write(channel, time_ns, fx.point_cloud(
                time_ns, frame_id, points[start:end], rgba[start:end]).encode())
        self._place(entity, frame_id)
        columns = list(rr.Points3D.columns(positions=points,
                                           colors=None if colors is None else rgba
                                           ).partition(counts))
        if radii is not None:
            radii = np.asarray(radii, dtype=float)
            if radii.ndim == 0:
                columns += rr.Points3D.columns(radii=np.full(ns.size, float(radii)))
            else:
                columns += rr.Points3D.columns(radii=radii).partition(counts)
        self.rerun.send_columns(entity, indexes=index, columns=columns)

    def line_strip3d(self, topic: str, t: float, points: np.ndarray, color=(255, 255, 255),
                     thickness: float = 0.002, frame_id: str = WORLD_FRAME,
                     entity_id: str | None = None) -> None:
        """A polyline through ``points`` (n, 3), metres, at time ``t``:
        :meth:`line_strip3d_series` at one time (``entity_id`` default: the topic)."""
        self.line_strip3d_series(topic, [t], [points], color, thickness, frame_id,
                                 [entity_id or topic])

    def line_strip3d_series(self, topic: str, t: np.ndarray, strips, color=(255, 255, 255),
                            thickness: float = 0.002, frame_id: str = WORLD_FRAME,
                            entity_ids: Sequence[str] | None = None) -> None:
        """One polyline per time: through ``strips[k]`` (p_k, 3), metres, at ``t[k]``;
        ``thickness`` in metres.

        MCAP: per time a ``foxglove.SceneUpdate`` with one entity holding a LINE_STRIP; its
        id is ``entity_ids[k]`` (default: the topic), so a strip replaces the last one with
        the same id, and strips with ids of their own add up (a path growing piece by
        piece). Rerun: ``LineStrips3D`` (one ``send_columns``; a layout shows earlier ones
        with a visible time range).
        """
        entity = _checked_topic(topic)
        ns, index = self._time_column(t)
        if not ns.size:
            return
        strips = [np.asarray(points, dtype=float).reshape(-1, 3) for points in strips]
        ids = [topic] * ns.size if entity_ids is None else list(entity_ids)
        if len(strips) != ns.size or len(ids) != ns.size:
            raise ValueError(f"{topic}: need {ns.size} strips and entity ids")
        rgba = fx.rgba_uint8(color, 1)
        channel = self._mcap.protobuf_channel(topic, fm.SceneUpdate)
        for time_ns, points, entity_id in zip(ns.tolist(), strips, ids):
            self._mcap.write(channel, time_ns, fx.scene_line_strip(
                time_ns, frame_id, entity_id, points, rgba[0], thickness).encode())
        self._place(entity, frame_id)
        self.rerun.send_columns(entity, indexes=index, columns=rr.LineStrips3D.columns(
            strips=strips, colors=np.broadcast_to(rgba, (ns.size, 4)),
            radii=np.full(ns.size, thickness / 2.0)))

    def arrow3d(self, topic: str, t: float, origin: np.ndarray, vector: np.ndarray,
                color=(255, 64, 64), frame_id: str = WORLD_FRAME) -> None:
        """Arrow(s) from ``origin`` along ``vector``, each (3,) or (n, 3), metres.

        MCAP: ``foxglove.SceneUpdate`` with one entity (id = topic) of ArrowPrimitives whose
        total length is |vector|. Rerun: ``Arrows3D``.
        """
        entity = _checked_topic(topic)
        origins = np.asarray(origin, dtype=float).reshape(-1, 3)
        vectors = np.asarray(vector, dtype=float).reshape(-1, 3)
        if origins.shape != vectors.shape:
            raise ValueError(f"{topic}: origin {origins.shape} and vector {vectors.shape} differ in shape")
        rgba = fx.rgba_uint8(color, origins.shape[0])
        ns = self._at(t)
        self._write(topic, ns, fx.scene_arrows(ns, frame_id, topic, origins, vectors, rgba))
        self._place(entity, frame_id)
        self.rerun.log(entity, rr.Arrows3D(origins=origins, vectors=vectors, colors=rgba))

    def box3d(self, topic: str, t: float, size, translation=None, q_xyzw=(0.0, 0.0, 0.0, 1.0),
              color=(240, 200, 30), frame_id: str = WORLD_FRAME) -> None:
        """A solid box of ``size`` (3,) m at ``translation`` (3,) m and orientation ``q_xyzw``
        in ``frame_id`` at time ``t``; ``translation`` None removes it:
        :meth:`box3d_series` at one time."""
        self.box3d_series(topic, [t], [size], [np.full(3, np.nan) if translation is None
                                               else translation], [q_xyzw], color, frame_id)

    def box3d_series(self, topic: str, t: np.ndarray, sizes, translations, q_xyzw,
                     colors=(240, 200, 30), frame_id: str = WORLD_FRAME) -> None:
        """One solid box per time ``t`` (n,): of ``sizes`` (n, 3) m at ``translations`` (n, 3) m
        and orientations ``q_xyzw`` (n, 4) in ``frame_id``; a NaN translation removes it
        (e.g. a lost sponge). ``colors``: one (3,)/(4,) or one per time (n, 3|4).

        MCAP: per time a ``foxglove.SceneUpdate`` with one frame-locked entity (id = topic)
        holding a CubePrimitive, or deleting it. Rerun: ``Boxes3D`` (an empty one removes
        it; ``send_columns``).
        """
        entity = _checked_topic(topic)
        t = np.asarray(t, dtype=float)
        ns, _ = self._time_column(t)
        if not ns.size:
            return
        sizes = np.asarray(sizes, dtype=float).reshape(-1, 3)
        translations = np.asarray(translations, dtype=float).reshape(-1, 3)
        q_xyzw = np.asarray(q_xyzw, dtype=float).reshape(-1, 4)
        if not sizes.shape[0] == translations.shape[0] == q_xyzw.shape[0] == ns.size:
            raise ValueError(f"{topic}: need {ns.size} sizes, translations and quaternions")
        rgba = fx.rgba_uint8(colors, ns.size)
        shown = np.isfinite(translations).all(axis=1)
        unit = fx.unit_quaternions(q_xyzw[shown])
        self._place(entity, frame_id)
        channel = self._mcap.protobuf_channel(topic, fm.SceneUpdate)
        for k, time_ns in enumerate(ns.tolist()):
            message = fx.scene_shapes(time_ns, [(topic, frame_id, [
                ("box", translations[k], q_xyzw[k], sizes[k], rgba[k])])]) if shown[k] \
                else fx.scene_deletion(time_ns, topic)
            self._mcap.write(channel, time_ns, message.encode())
        if shown.any():
            self.rerun.send_columns(entity, indexes=self._time_column(t[shown])[1],
                                    columns=rr.Boxes3D.columns(
                                        half_sizes=0.5 * sizes[shown],
                                        centers=translations[shown], quaternions=unit,
                                        colors=rgba[shown],
                                        fill_mode=[rr.components.FillMode.Solid] * len(unit)))
        if not shown.all():
            removed = np.count_nonzero(~shown)
            self.rerun.send_columns(entity, indexes=self._time_column(t[~shown])[1],
                                    columns=rr.Boxes3D.columns(half_sizes=np.zeros((0, 3))
                                                               ).partition(np.zeros(removed,
                                                                                    int)))

    def shapes(self, topic: str, t: float, entities) -> None:
        """Solids attached to frames, for Foxglove's 3D panel (e.g. a robot's links): MCAP
        only, one ``foxglove.SceneUpdate`` of frame-locked entities (see
        :func:`wipelab.logs.foxglove_messages.scene_shapes` for ``entities``). Rerun draws
        the same body from its own description (e.g. the URDF)."""
        _checked_topic(topic)
        ns = seconds_to_ns(t)
        self._write(topic, ns, fx.scene_shapes(ns, entities))

    def image_overlay(self, topic: str, t: float, frame_id: str, lines=(), points=(),
                      line_color=(255, 60, 60), point_color=(80, 220, 80)) -> None:
        """Drawing over a camera's images at time ``t``: line segments (m, 2, 2) and points
        (k, 2) in pixels: :meth:`image_overlay_series` at one time."""
        self.image_overlay_series(topic, [t], frame_id, [lines], [points], line_color,
                                  point_color)

    def image_overlay_series(self, topic: str, t: np.ndarray, frame_id: str, lines, points,
                             line_colors=(255, 60, 60), point_color=(80, 220, 80)) -> None:
        """Drawings over a camera's images at times ``t`` (n,): line segments ``lines[k]``
        (m_k, 2, 2) and points ``points[k]`` (p_k, 2) in pixels, origin at the top-left corner
        of the top-left pixel; the lines' colour one (3,) or one per time (n, 3).

        MCAP: one ``foxglove.ImageAnnotations`` per time (Foxglove's Image panel draws them
        over the camera's image topic). Rerun: ``LineStrips2D`` and ``Points2D`` in the
        image plane of the camera whose optical frame is ``frame_id`` (one ``send_columns``).
        """
        entity = _checked_topic(topic)
        ns, index = self._time_column(t)
        if not ns.size:
            return
        lines = [np.asarray(segments, dtype=float).reshape(-1, 2, 2) for segments in lines]
        points = [np.asarray(dots, dtype=float).reshape(-1, 2) for dots in points]
        if len(lines) != ns.size or len(points) != ns.size:
            raise ValueError(f"{topic}: need {ns.size} sets of lines and of points")
        line_rgba = fx.rgba_uint8(line_colors, ns.size)
        point_rgba = fx.rgba_uint8(point_color, 1)[0]
        channel = self._mcap.protobuf_channel(topic, fm.ImageAnnotations)
        for time_ns, segments, colour, dots in zip(ns.tolist(), lines, line_rgba, points):
            self._mcap.write(channel, time_ns, fx.image_annotations(
                time_ns, segments, colour, dots, point_rgba, 2.0).encode())
        self._place(entity, frame_id + IMAGE_PLANE_SUFFIX)
        self.rerun.send_columns(entity, indexes=index, columns=[
            *rr.LineStrips2D.columns(strips=np.concatenate([np.zeros((0, 2, 2)), *lines])
                                     ).partition([len(segments) for segments in lines]),
            *rr.LineStrips2D.columns(colors=line_rgba, radii=np.ones(ns.size)),
            *rr.Points2D.columns(positions=np.concatenate([np.zeros((0, 2)), *points])
                                 ).partition([len(dots) for dots in points]),
            *rr.Points2D.columns(colors=np.broadcast_to(point_rgba, (ns.size, 4)),
                                 radii=np.full(ns.size, 1.5))])

    def events(self, topic: str, t: np.ndarray, texts: Sequence[str], level: str = "info") -> None:
        """Text events (what happened when) at times ``t`` (n,) in seconds.

        MCAP: ``foxglove.Log`` (Foxglove's Log panel), name = the stage. Rerun: ``TextLog``.
        """
        entity = _checked_topic(topic)
        for time, text in zip(np.atleast_1d(t).tolist(), texts):
            ns = self._at(time)
            self._write(topic, ns, fx.log_message(ns, level, str(text), self.stage))
            self.rerun.log(entity, rr.TextLog(str(text), level=level.upper()))

    def states(self, topic: str, t: np.ndarray, states: Sequence[str],
               palette: dict[str, tuple] | None = None) -> None:
        """A state that changes at times ``t`` (n,) in seconds to ``states`` (n,) (text).

        MCAP: JSON channel ``wipelab.State``, one message ``{"state": ...}`` per change
        (Foxglove's State Transitions panel plots ``/topic.state``). Rerun: ``StateChange``
        (a state timeline view) styled by a static ``StateConfiguration`` with ``palette``
        (state -> (3,) uint8 colour).
        """
        entity = _checked_topic(topic)
        ns = seconds_array_to_ns(np.atleast_1d(t))
        states = [str(s) for s in states]
        if len(states) != ns.size:
            raise ValueError(f"{topic}: need {ns.size} states, got {len(states)}")
        schema = {"title": _STATE_SCHEMA, "type": "object",
                  "properties": {"state": {"type": "string"}}, "required": ["state"]}
        channel = self._mcap.json_channel(topic, _STATE_SCHEMA, schema)
        for time_ns, state in zip(ns.tolist(), states):
            self._mcap.write(channel, time_ns, json_bytes({"state": state}))
        if palette:
            values = list(palette)
            self.rerun.log(entity, rr.StateConfiguration(
                values=values, colors=fx.rgba_uint8(np.array([palette[v] for v in values]),
                                                    len(values))), static=True)
        self.rerun.send_columns(entity, indexes=[rr.TimeColumn(
            TIMELINE, duration=ns.astype("timedelta64[ns]"))],
            columns=rr.StateChange.columns(state=states))

    def phase_curves(self, topic: str, t: float, chart: PhaseChart, phase: np.ndarray,
                     curves: dict[str, np.ndarray], colors: dict[str, tuple],
                     extra: dict | None = None) -> None:
        """Curves over one period of the phase at time ``t``: values (n,) per name at
        ``phase`` (n,) rad.

        MCAP: JSON channel ``wipelab.PhaseCurves``, one message ``{"phase_rad": [...],
        name: [...], ...}`` plus ``extra`` (Foxglove's Plot panel plots ``/topic.name``
        against ``/topic.phase_rad``); names as for :meth:`scalars`. Rerun: ``LineStrips2D``
        in ``chart`` coordinates, one colour per curve; draw the axes once with
        :meth:`phase_chart` and name the colours with :meth:`phase_legend`.
        """
        entity = _checked_topic(topic)
        unplottable = [n for n in curves if not PLOTTABLE_NAME.fullmatch(n) or n == "phase_rad"]
        if unplottable:
            raise ValueError(f"{topic}: curve names may hold only letters, digits and '_' "
                             f"and not be phase_rad, got {unplottable}")
        ns = self._at(t)
        schema = {"title": "wipelab.PhaseCurves", "type": "object",
                  "properties": {name: {"type": "array"} for name in ["phase_rad", *curves]},
                  "required": ["phase_rad", *sorted(curves)]}
        channel = self._mcap.json_channel(topic, "wipelab.PhaseCurves", schema)
        self._mcap.write(channel, ns, json_bytes({"phase_rad": np.asarray(phase), **curves,
                                                  **(extra or {})}))
        strips, strip_colors = [], []
        for name, values in curves.items():
            pieces = chart.strips(phase, values)
            strips += pieces
            strip_colors += [fx.rgba_uint8(colors[name], 1)[0]] * len(pieces)
        self.rerun.log(entity, rr.LineStrips2D(strips, colors=strip_colors, radii=1.0,
                                               draw_order=10.0))

    def phase_chart(self, topic: str, chart: PhaseChart,
                    references: dict[str, float] | None = None) -> None:
        """The axes of the chart in which :meth:`phase_curves` draws ``topic``, with
        labelled reference lines (label -> value); Rerun only."""
        chart.log_axes(self.rerun, _checked_topic(topic), references)

    def phase_legend(self, topic: str, chart: PhaseChart, entries: dict[str, tuple]) -> None:
        """What the colours of ``topic``'s curves mean (label -> (3,) uint8); Rerun only."""
        chart.log_legend(self.rerun, _checked_topic(topic), entries)

    def transforms(self, t: float, transforms: Sequence[tuple]) -> None:
        """Frame transforms ``[(parent, child, translation (3,), q_xyzw (4,)), ...]`` at ``t``.

        Each places ``child`` in ``parent``: p_parent = R(q) p_child + translation (metres;
        quaternion (x, y, z, w), normalised here). MCAP: one ``foxglove.FrameTransforms`` on
        ``/tf``. Rerun: ``Transform3D`` with ``parent_frame``/``child_frame`` on ``/tf/<child>``.
        """
        ns = self._at(t)
        self._write(TF_TOPIC, ns, fx.frame_transforms(ns, transforms))
        for parent, child, translation, q_xyzw in transforms:
            self.rerun.log(_checked_topic(f"{TF_TOPIC}/{child}"), rr.Transform3D(
                translation=np.asarray(translation, dtype=float).reshape(3),
                quaternion=fx.unit_quaternion(q_xyzw),
                parent_frame=rerun_frame(parent), child_frame=child))

    def pose(self, topic: str, t: float, frame_id: str, translation: np.ndarray,
             q_xyzw: np.ndarray) -> None:
        """A pose: ``translation`` (3,) m and quaternion (x, y, z, w) in ``frame_id``.

        MCAP: ``foxglove.PoseInFrame``. Rerun: ``Transform3D`` of the entity's own frame
        relative to ``frame_id``, drawn as axes (``TransformAxes3D``).
        """
        entity = _checked_topic(topic)
        ns = self._at(t)
        self._write(topic, ns, fx.pose_in_frame(ns, frame_id, translation, q_xyzw))
        frames = {} if frame_id == WORLD_FRAME else \
            {"parent_frame": frame_id, "child_frame": f"tf#{entity}"}
        self.rerun.log(entity, rr.Transform3D(translation=np.asarray(translation, dtype=float).reshape(3),
                                              quaternion=fx.unit_quaternion(q_xyzw), **frames),
                       rr.TransformAxes3D(POSE_AXIS_LENGTH))

    # -- whole series at once (MCAP: one message per time as above; Rerun: send_columns) ---
    def in_time_order(self):
        """A block whose MCAP messages are written when it ends, in time order (see
        :meth:`~wipelab.logs.mcap_log.McapLog.in_time_order`): several series logged in it
        one after the other lie in the file as if they had been logged time by time."""
        return self._mcap.in_time_order()

    def _time_column(self, t: np.ndarray) -> tuple[np.ndarray, list]:
        ns = seconds_array_to_ns(t)
        return ns, [rr.TimeColumn(TIMELINE, duration=ns.astype("timedelta64[ns]"))]

    def transform_series(self, t: np.ndarray, frames: Sequence[tuple]) -> None:
        """Moving frames over time: ``[(parent, child, translations (n, 3), q_xyzw (n, 4)), ...]``
        at times ``t`` (n,) in seconds.

        The same as :meth:`transforms` at each time (MCAP: one ``foxglove.FrameTransforms``
        per time holding every frame), with one ``send_columns`` per frame on the Rerun side.
        """
        ns, index = self._time_column(t)
        frames = [(parent, child, np.asarray(translations, dtype=float).reshape(-1, 3),
                   np.asarray(quaternions, dtype=float).reshape(-1, 4))
                  for parent, child, translations, quaternions in frames]
        for parent, child, translations, quaternions in frames:
            if translations.shape[0] != ns.size or quaternions.shape[0] != ns.size:
                raise ValueError(f"frame {child!r}: need {ns.size} translations and quaternions")
        channel = self._mcap.protobuf_channel(TF_TOPIC, fm.FrameTransforms)
        times = ns.tolist()
        for time_ns, message in zip(times, fx.frame_transforms_series(times, frames)):
            self._mcap.write(channel, time_ns, message.encode())
        for parent, child, translations, quaternions in frames:
            unit = fx.unit_quaternions(quaternions)
            self.rerun.send_columns(_checked_topic(f"{TF_TOPIC}/{child}"), indexes=index,
                                    columns=rr.Transform3D.columns(
                                        translation=translations, quaternion=unit,
                                        parent_frame=[rerun_frame(parent)] * ns.size,
                                        child_frame=[child] * ns.size))

    def pose_series(self, topic: str, t: np.ndarray, frame_id: str, translations: np.ndarray,
                    q_xyzw: np.ndarray) -> None:
        """Poses (n, 3) and (n, 4) at times ``t`` (n,): :meth:`pose` at each time, with one
        ``send_columns`` on the Rerun side (axes drawn by a static ``TransformAxes3D``)."""
        entity = _checked_topic(topic)
        ns, index = self._time_column(t)
        translations = np.asarray(translations, dtype=float).reshape(-1, 3)
        quaternions = np.asarray(q_xyzw, dtype=float).reshape(-1, 4)
        unit = fx.unit_quaternions(quaternions)
        if translations.shape[0] != ns.size or unit.shape[0] != ns.size:
            raise ValueError(f"{topic}: need {ns.size} translations and quaternions")
        channel = self._mcap.protobuf_channel(topic, fm.PoseInFrame)
        times = ns.tolist()
        for time_ns, message in zip(times, fx.poses_in_frame(times, frame_id, translations,
                                                             quaternions)):
            self._mcap.write(channel, time_ns, message.encode())
        frames = {} if frame_id == WORLD_FRAME else \
            {"parent_frame": [frame_id] * ns.size, "child_frame": [f"tf#{entity}"] * ns.size}
        self.rerun.log(entity, rr.TransformAxes3D(POSE_AXIS_LENGTH), static=True)
        self.rerun.send_columns(entity, indexes=index, columns=rr.Transform3D.columns(
            translation=translations, quaternion=unit, **frames))

    def arrow_series(self, topic: str, t: np.ndarray, origins: np.ndarray, vectors: np.ndarray,
                     color=(255, 64, 64), frame_id: str = WORLD_FRAME) -> None:
        """One arrow per time: origins (n, 3) and vectors (n, 3) at times ``t`` (n,), metres;
        :meth:`arrow3d` at each time, with one ``send_columns`` on the Rerun side."""
        entity = _checked_topic(topic)
        ns, index = self._time_column(t)
        origins = np.asarray(origins, dtype=float).reshape(-1, 3)
        vectors = np.asarray(vectors, dtype=float).reshape(-1, 3)
        if origins.shape != vectors.shape or origins.shape[0] != ns.size:
            raise ValueError(f"{topic}: need {ns.size} origins and vectors")
        rgba = fx.rgba_uint8(color, 1)
        channel = self._mcap.protobuf_channel(topic, fm.SceneUpdate)
        for time_ns, origin, vector in zip(ns.tolist(), origins, vectors):
            self._mcap.write(channel, time_ns, fx.scene_arrows(time_ns, frame_id, topic,
                                                               origin[None], vector[None],
                                                               rgba).encode())
        self._place(entity, frame_id)
        self.rerun.send_columns(entity, indexes=index, columns=rr.Arrows3D.columns(
            origins=origins, vectors=vectors,
            colors=np.broadcast_to(rgba, (ns.size, 4))))

    def camera_calibration(self, topic: str, t: float, K: np.ndarray, D: np.ndarray, width: int,
                           height: int, frame_id: str, R: np.ndarray | None = None,
                           P: np.ndarray | None = None,
                           image_plane_distance: float | None = None) -> None:
        """Calibration of a pinhole camera whose optical frame is ``frame_id``.

        K (3, 3) pixels, D (5,) OpenCV (k1, k2, p1, p2, k3), optional R (3, 3) and P (3, 4).
        MCAP: ``foxglove.CameraCalibration`` (``plumb_bob``). Rerun: ``Pinhole`` from
        ``frame_id`` to ``<frame_id>_image_plane`` (RDF camera axes, the default), the frame in which
        images with the same ``frame_id`` are shown (as ``rerun mcap convert`` does);
        ``image_plane_distance`` (m) is the length of the frustum a 3D view draws.
        """
        entity = _checked_topic(topic)
        ns = self._at(t)
        self._write(topic, ns, fx.camera_calibration(ns, K, D, width, height, frame_id, R, P))
        self.rerun.log(entity, rr.Pinhole(
            image_from_camera=np.asarray(K, dtype=float).reshape(3, 3), resolution=[int(width), int(height)],
            parent_frame=rerun_frame(frame_id),  # camera axes RDF: Rerun's default, and
            # unlike an explicit camera_xyz, not drawn as big arrows in every 3D view
            child_frame=frame_id + IMAGE_PLANE_SUFFIX, image_plane_distance=image_plane_distance))

    def compressed_image(self, topic: str, t: float, data: bytes, frame_id: str) -> None:
        """One encoded image (JPEG, PNG or WebP bytes) from the camera with optical frame ``frame_id``.

        MCAP: ``foxglove.CompressedImage``. Rerun: ``EncodedImage`` in ``<frame_id>_image_plane``.
        """
        entity = _checked_topic(topic)
        data = bytes(data)
        image_format = fx.image_format(data)
        ns = self._at(t)
        self._write(topic, ns, fx.compressed_image(ns, data, frame_id, image_format))
        self._place(entity, frame_id + IMAGE_PLANE_SUFFIX)
        self.rerun.log(entity, rr.EncodedImage(contents=data, media_type=f"image/{image_format}"))

    def video(self, topic: str, mp4_path: str | os.PathLike, frame_times: np.ndarray,
              frame_id: str | None = None) -> None:
        """A video file (H.264, H.265 or AV1, no B-frames) whose frame i shows data time ``frame_times[i]``.

        Rerun: the file as a static ``AssetVideo`` plus one ``VideoFrameReference`` per frame
        on the timeline (the .rrd grows by the file's size). MCAP: one
        ``foxglove.CompressedVideo`` per frame (Annex B / OBU access units). ``frame_times``
        (m,) may cover the first m <= n frames. ``frame_id``: camera optical frame; the images
        are shown in ``<frame_id>_image_plane`` when given.

        Raises
        ------
        wipelab.errors.InputError
            If the file's codec is not H.264/H.265/AV1 or it has B-frames.
        ValueError
            If ``frame_times`` has more entries than the video has frames.
        """
        entity = _checked_topic(topic)
        frame_ns = seconds_array_to_ns(frame_times)
        foxglove_format, units = access_units(mp4_path)
        asset = rr.AssetVideo(path=mp4_path)
        video_ns = asset.read_frame_timestamps_nanos()
        if frame_ns.size > video_ns.size:
            raise ValueError(f"{mp4_path}: has {video_ns.size} frames, got {frame_ns.size} frame times")
        for ns, unit in zip(frame_ns.tolist(), units):
            self._write(topic, ns, fx.compressed_video(ns, unit, frame_id or "", foxglove_format))
        if frame_id is not None:
            self._place(entity, frame_id + IMAGE_PLANE_SUFFIX)
        self.rerun.log(entity, asset, static=True)
        self.rerun.send_columns(
            entity, indexes=[rr.TimeColumn(TIMELINE, duration=frame_ns.astype("timedelta64[ns]"))],
            columns=rr.VideoFrameReference.columns_nanos(video_ns[:frame_ns.size]))

    def video_sample(self, topic: str, t: float, data: bytes, frame_id: str) -> None:
        """One access unit of an H.264 Annex B stream (no B-frames) encoded while logging
        (a live camera; :class:`~wipelab.logs.video_encoder.LiveVideoEncoder`), showing
        data time ``t``; the images are shown in ``<frame_id>_image_plane``.

        MCAP: ``foxglove.CompressedVideo``. Rerun: ``VideoStream`` (H.264 codec, logged
        statically with the first sample).
        """
        entity = _checked_topic(topic)
        ns = self._at(t)
        self._write(topic, ns, fx.compressed_video(ns, data, frame_id, "h264"))
        if entity not in self._video_streams:
            self._video_streams.add(entity)
            self.rerun.log(entity, rr.CoordinateFrame(frame_id + IMAGE_PLANE_SUFFIX),
                           rr.VideoStream(codec=rr.VideoCodec.H264), static=True)
        self.rerun.log(entity, rr.VideoStream.from_fields(sample=bytes(data)))

    def json(self, topic: str, t: float, message: dict, schema_name: str,
             schema: dict | None = None) -> None:
        """Any JSON-serialisable ``message`` on a named JSON-schema channel.

        MCAP: schema ``schema_name`` (encoding jsonschema, ``{"type": "object"}`` if None),
        message encoding json, canonical JSON (sorted keys; numpy arrays as lists; NaN as
        null). Rerun: a ``TextDocument`` (Markdown with the pretty-printed JSON).
        """
        entity = _checked_topic(topic)
        ns = self._at(t)
        channel = self._mcap.json_channel(topic, schema_name, schema or {"type": "object"})
        data = json_bytes(message)
        self._mcap.write(channel, ns, data)
        pretty = json.dumps(json.loads(data), indent=2, sort_keys=True, ensure_ascii=False)
        self.rerun.log(entity, rr.TextDocument(f"`{schema_name}`\n\n```json\n{pretty}\n```",
                                               media_type=rr.MediaType.MARKDOWN))

    def attach(self, name: str, data: bytes, media_type: str = "application/octet-stream") -> None:
        """Attach bytes to the MCAP (calibration files, configs); MCAP only."""
        self._mcap.attachment(name, bytes(data), media_type)
