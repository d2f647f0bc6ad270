"""Reading back what :class:`wipelab.logs.StageRecorder` wrote (tests, report, pipeline).

MCAP through the ``mcap`` reader (CRCs validated) with JSON and protobuf decoding; ``.rrd``
through ``rerun.chunk.RrdReader``.
"""

from __future__ import annotations

import json
import os
from collections import Counter
from typing import Any

import numpy as np
import pyarrow as pa
from google.protobuf.descriptor import FieldDescriptor
from mcap.decoder import DecoderFactory as McapDecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory
from rerun.chunk import RrdReader

from wipelab.logs.foxglove_messages import POINT_CLOUD_DTYPE
from wipelab.logs.mcap_log import JSON
from wipelab.logs.recorder import METADATA_INPUTS, METADATA_PARAMETERS, TIMELINE


class _JsonDecoderFactory(McapDecoderFactory):
    def decoder_for(self, message_encoding, schema):
        return (lambda data: json.loads(data)) if message_encoding == JSON else None


def _reader(stream):
    return make_reader(stream, validate_crcs=True,
                       decoder_factories=[_JsonDecoderFactory(), ProtobufDecoderFactory()])


def protobuf_to_dict(message) -> dict[str, Any]:
    """A decoded protobuf message as a dict: every field (defaults included), bytes kept as
    bytes, enums as their names, unset sub-messages as None."""
    out = {}
    for field in message.DESCRIPTOR.fields:
        value = getattr(message, field.name)
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            if field.is_repeated:
                value = [protobuf_to_dict(v) for v in value]
            else:
                value = protobuf_to_dict(value) if message.HasField(field.name) else None
        elif field.type == FieldDescriptor.TYPE_ENUM:
            names = field.enum_type.values_by_number
            value = [names[v].name for v in value] if field.is_repeated else names[value].name
        elif field.is_repeated:
            value = list(value)
        out[field.name] = value
    return out


def read_mcap_topic(path: str | os.PathLike, topic: str) -> list[tuple[int, dict[str, Any]]]:
    """All messages of ``topic`` in log-time order as ``(log_time_ns, message dict)``.

    JSON messages decode to what was written; protobuf ones via :func:`protobuf_to_dict`.
    """
    with open(path, "rb") as f:
        out = []
        for _, _, message, decoded in _reader(f).iter_decoded_messages(topics=[topic], log_time_order=True):
            out.append((message.log_time, decoded if isinstance(decoded, (dict, list)) else protobuf_to_dict(decoded)))
        return out


def mcap_topics(path: str | os.PathLike) -> dict[str, dict[str, Any]]:
    """topic -> {"schema": name, "schema_encoding", "message_encoding", "message_count"} (from the summary)."""
    with open(path, "rb") as f:
        summary = _reader(f).get_summary()
    if summary is None:
        raise ValueError(f"{path}: MCAP file has no summary section")
    counts = summary.statistics.channel_message_counts if summary.statistics else Counter()
    out = {}
    for channel_id, channel in sorted(summary.channels.items()):
        schema = summary.schemas.get(channel.schema_id)
        out[channel.topic] = {"schema": schema.name if schema else "",
                              "schema_encoding": schema.encoding if schema else "",
                              "message_encoding": channel.message_encoding,
                              "message_count": counts.get(channel_id, 0)}
    return out


def mcap_metadata(path: str | os.PathLike) -> dict[str, dict[str, str]]:
    """MCAP metadata records: name -> {key: value}."""
    with open(path, "rb") as f:
        return {record.name: dict(record.metadata) for record in _reader(f).iter_metadata()}


def mcap_parameters(path: str | os.PathLike) -> dict[str, Any]:
    """The stage parameters stored by the recorder (JSON values decoded)."""
    return {k: json.loads(v) for k, v in mcap_metadata(path)[METADATA_PARAMETERS].items()}


def mcap_input_hashes(path: str | os.PathLike) -> dict[str, str]:
    """role -> sha256 of the stage inputs stored by the recorder."""
    suffix = ".sha256"
    return {k[:-len(suffix)]: v for k, v in mcap_metadata(path)[METADATA_INPUTS].items() if k.endswith(suffix)}


def mcap_attachments(path: str | os.PathLike) -> dict[str, tuple[str, bytes]]:
    """Attachments: name -> (media type, data)."""
    with open(path, "rb") as f:
        return {a.name: (a.media_type, bytes(a.data)) for a in _reader(f).iter_attachments()}


def read_mcap_scalars(path: str | os.PathLike, topic: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """A ``StageRecorder.scalars`` series from the MCAP: t (n,) s, values (n, k), names (k,).

    Columns are in the order of the names sorted; null values come back as NaN.
    """
    messages = read_mcap_topic(path, topic)
    if not messages:
        raise KeyError(f"{path}: no messages on {topic}")
    names = sorted(messages[0][1])
    t = np.array([ns for ns, _ in messages], dtype=np.int64) / 1e9
    values = np.array([[np.nan if m[n] is None else m[n] for n in names] for _, m in messages], dtype=float)
    return t, values, names


def point_cloud_points(message: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """A decoded ``foxglove.PointCloud`` written by the recorder -> points (n, 3), rgba (n, 4) uint8."""
    packed = np.frombuffer(message["data"], dtype=POINT_CLOUD_DTYPE)
    points = np.stack([packed["x"], packed["y"], packed["z"]], axis=1).astype(float)
    return points, packed["rgba"].copy()


def rrd_record_batches(path: str | os.PathLike, entity: str, blueprint: bool = False) -> list[pa.RecordBatch]:
    """Record batches of every chunk logged exactly on ``entity`` (data store, or the blueprint)."""
    reader = RrdReader(path)
    stores = reader.blueprints() if blueprint else reader.recordings()
    if not stores:
        raise ValueError(f"{path}: no {'blueprint' if blueprint else 'recording'} store")
    return [chunk.to_record_batch() for chunk in reader.stream(store=stores[0]).to_chunks()
            if chunk.entity_path == entity]


def rrd_column(path: str | os.PathLike, entity: str, component: str) -> tuple[np.ndarray | None, list]:
    """One component of ``entity`` over all its chunks: (times (n,) s on "time" or None if
    static, values (n,) as Python lists), sorted by time."""
    times, values = [], []
    column = f"{entity}:{component}"
    for batch in rrd_record_batches(path, entity):
        names = batch.schema.names
        name = column if column in names else component if component in names else None
        if name is None:
            continue
        values.extend(batch.column(name).to_pylist())
        if TIMELINE in names:
            times.extend(batch.column(TIMELINE).cast(pa.int64()).to_pylist())
    if not times:
        return None, values
    order = np.argsort(np.array(times), kind="stable")
    return np.array(times, dtype=np.int64)[order] / 1e9, [values[i] for i in order]


def read_rrd_scalars(path: str | os.PathLike, entity: str) -> tuple[np.ndarray, np.ndarray]:
    """A scalars series from the ``.rrd``: t (n,) seconds on "time", values (n, k)."""
    t, values = rrd_column(path, entity, "Scalars:scalars")
    if t is None:
        raise KeyError(f"{path}: no time-stamped Scalars on {entity}")
    return t, np.array(values, dtype=float)


def rrd_blueprint_views(path: str | os.PathLike) -> list[tuple[str, str]]:
    """The default blueprint's views as sorted (class identifier, space origin) pairs,
    e.g. ``("TimeSeries", "/oscillators")``."""
    reader = RrdReader(path)
    views = []
    for store in reader.blueprints():
        for chunk in reader.stream(store=store).to_chunks():
            batch = chunk.to_record_batch()
            kinds = [n for n in batch.schema.names if n.endswith("ViewBlueprint:class_identifier")]
            origins = [n for n in batch.schema.names if n.endswith("ViewBlueprint:space_origin")]
            if kinds and origins:
                for kind, origin in zip(batch.column(kinds[0]).to_pylist(), batch.column(origins[0]).to_pylist()):
                    views.append((_first(kind), _first(origin)))
    return sorted(views)


def _first(value):
    return value[0] if isinstance(value, list) else value
