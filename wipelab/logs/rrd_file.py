"""Byte-reproducible Rerun ``.rrd`` files.

The Rerun SDK stamps everything it writes with fresh ids: chunk ids and row ids are TUIDs
(wall-clock nanoseconds + a random counter), blueprint views and containers get ``uuid4``
ids, the blueprint store gets a random id, blueprint rows carry a wall-clock ``log_time``,
and the batcher cuts chunks on a timer. None of that is data, so a recording is captured
first (``<name>.rrd.part``) with a timer-free batcher and then rewritten canonically:

1. chunks are ordered by their first row id (the order in which they were logged) and get
   counter ids in that order; every row id is replaced by its rank among the store's row
   ids (so "logged later" stays "later"), streaming, so a recording never has to fit in
   memory;
2. the ``log_time`` timeline of blueprint rows is dropped, view/container ids are ``uuid5``
   of their place in the layout (:func:`deterministic_blueprint`);
3. the row ids of the ``SetStoreInfo`` envelopes (TUIDs again) are set to counters, the
   blueprint store id to one derived from the recording id, and the footer (one chunk
   manifest per store, which Rerun writes in hash-map order with hash-map-ordered columns)
   is rewritten with stores and columns sorted, then re-checksummed.

Step 3 edits the RRD 0.41 framing: ``RRF2`` stream header, 16-byte message headers
(kind, length), an End message whose payload is the ``RrdFooter`` protobuf, and a 32-byte
stream footer (offset, length, xxh32 with Rerun's seed, ``RRF2FOOT``, version). Anything
unexpected raises instead of writing a doubtful file; ``rerun rrd verify`` checks the result
in the tests.

The result holds the same data and blueprint as the capture, and passes ``rerun rrd verify``.
"""

from __future__ import annotations

import copy
import itertools
import struct
import uuid
from datetime import timedelta
from pathlib import Path
from typing import Iterator

import numpy as np
import pyarrow as pa
import pyarrow.ipc as ipc
import xxhash
import rerun as rr
import rerun.blueprint as rrb
from rerun import bindings
from rerun.chunk import Chunk, RrdReader
from rerun.recording_stream import RecordingStream

ROW_ID_COLUMN = "rerun.controls.RowId"
CHUNK_ID_KEY = b"rerun:id"
#: Wall-clock timeline the SDK adds to blueprint rows; dropped.
LOG_TIME = "log_time"

#: Capture batcher: no timer, so chunk boundaries depend on the logged data only.
CAPTURE_BATCHER = rr.ChunkBatcherConfig(flush_tick=timedelta(days=3650), flush_num_bytes=4 << 20,
                                        flush_num_rows=1 << 20)

_RRD_MAGIC = b"RRF2"
_STREAM_HEADER_BYTES = 12  # magic, version, options
_MESSAGE_HEADER = struct.Struct("<QQ")  # kind, payload length
_KIND_END, _KIND_SET_STORE_INFO = 0, 1
# SetStoreInfo payload starts with field 1 (row_id: Tuid {fixed64 time_ns = 1; fixed64 inc = 2}).
_STORE_INFO_ROW_ID_PREFIX = b"\x0a\x12\x09"
# Stream footer: footer offset u64, footer length u64, xxh32(footer) u32, b"RRF2FOOT", version u32.
_STREAM_FOOTER = struct.Struct("<QQI8sI")
_FOOTER_MAGIC = b"RRF2FOOT"
_FOOTER_CRC_SEED = 7850921
_LZ4 = pa.Codec("lz4_raw")
_LZ4_COMPRESSION = 2
#: Bytes at the start of a message payload that hold its envelope (store id, row id).
_ENVELOPE_BYTES = 256
_BLUEPRINT_NAMESPACE = uuid.UUID("a3c5e0f1-3c1e-4c55-9f3e-7a4b2d1c0e99")


def deterministic_blueprint(blueprint: rrb.BlueprintLike, key: str) -> rrb.Blueprint:
    """A copy of ``blueprint`` as a Blueprint whose view, container and visualizer-override
    ids are uuid5(key, place in the layout).

    The containers and views are copied one by one (shallow): a deep copy would also copy
    the Arrow arrays of their properties, and that loses the non-null flags of nested
    fields, which the viewer's blueprint validation then rejects.
    """
    blueprint = copy.copy(blueprint.to_blueprint())

    def visit(part, position: str):
        part = copy.copy(part)
        if hasattr(part, "id"):
            part.id = uuid.uuid5(_BLUEPRINT_NAMESPACE, f"{key}/{position}")
        if isinstance(part, rrb.View) and part.visualizer_overrides:
            part.visualizer_overrides = {
                path: _deterministic_visualizers(overrides, f"{key}/{position}/{path}")
                for path, overrides in part.visualizer_overrides.items()}
        if isinstance(part, rrb.Container):
            part.contents = [visit(child, f"{position}/{i}")
                             if isinstance(child, (rrb.Container, rrb.View)) else child
                             for i, child in enumerate(part.contents)]
        return part

    blueprint.root_container = visit(blueprint.root_container, "root")
    return blueprint


def _deterministic_visualizers(overrides, key: str) -> list:
    """A view's overrides of one entity with the visualizers' ids uuid5(key, index) (the SDK
    draws them with uuid4); other overrides (time ranges, ...) unchanged."""
    listed = list(overrides) if isinstance(overrides, (list, tuple)) else [overrides]
    out = []
    for i, override in enumerate(listed):
        if isinstance(override, rrb.VisualizableArchetype):
            override = override.visualizer()
        if isinstance(override, rrb.Visualizer):
            override = copy.copy(override)
            override.id = uuid.uuid5(_BLUEPRINT_NAMESPACE, f"{key}/{i}")
        out.append(override)
    return out


def _row_ids(chunk: Chunk) -> np.ndarray:
    """The chunk's row ids (n,) as 16-byte strings; their byte order is their time order."""
    rows = chunk.to_record_batch().column(ROW_ID_COLUMN)
    storage = rows.storage if isinstance(rows, pa.ExtensionArray) else rows
    return np.frombuffer(storage.buffers()[1], dtype="S16", count=len(storage), offset=16 * storage.offset)


def _renumbered(chunk: Chunk, chunk_id: int, row_ids: np.ndarray) -> Chunk:
    """``chunk`` with id ``chunk_id``, row ids ``row_ids`` (n,) and no ``log_time`` column."""
    batch = chunk.to_record_batch()
    if LOG_TIME in batch.schema.names:
        batch = batch.drop_columns([LOG_TIME])
    n = batch.num_rows
    ids = np.zeros((n, 2), dtype=">u8")  # a TUID is (time_ns, inc), big-endian
    ids[:, 1] = row_ids
    index = batch.schema.get_field_index(ROW_ID_COLUMN)
    field = batch.schema.field(index)
    storage = pa.FixedSizeBinaryArray.from_buffers(pa.binary(16), n, [None, pa.py_buffer(ids.tobytes())])
    column = pa.ExtensionArray.from_storage(field.type, storage) \
        if isinstance(field.type, pa.ExtensionType) else storage
    batch = batch.set_column(index, field, column)
    metadata = {**batch.schema.metadata, CHUNK_ID_KEY: f"chunk_{chunk_id:032X}".encode()}
    renumbered, = Chunk.from_record_batch(batch.replace_schema_metadata(metadata))
    return renumbered


def _in_logging_order(reader: RrdReader, store, chunk_ids: Iterator[int], sink) -> None:
    """Pass the store's chunks to ``sink`` in the order they were logged, renumbered.

    A chunk's new id comes from ``chunk_ids`` in that order; a row's new id is its rank
    among all row ids of the store (1-based), so "logged later" stays "later" exactly.
    Two streaming passes (row ids first, then the chunks through a reorder buffer: they are
    out of order only within one batcher flush), so a recording never has to fit in memory.
    """
    firsts: list[bytes] = []
    ids: list[np.ndarray] = []

    def collect(chunk: Chunk) -> list:
        rows = _row_ids(chunk)
        firsts.append(np.sort(rows)[0])
        ids.append(rows.copy())
        return []

    reader.stream(store=store).flat_map(collect).to_chunks()
    all_ids = np.sort(np.concatenate(ids)) if ids else np.array([], dtype="S16")
    rank = {key: i for i, key in enumerate(sorted(firsts))}
    pending: dict[int, Chunk] = {}
    expected = 0

    def release(chunk: Chunk) -> list:
        nonlocal expected
        pending[rank[np.sort(_row_ids(chunk))[0]]] = chunk
        while expected in pending:
            chunk = pending.pop(expected)
            rows = np.searchsorted(all_ids, _row_ids(chunk)) + 1
            sink(_renumbered(chunk, next(chunk_ids), rows))
            expected += 1
        return []

    reader.stream(store=store).flat_map(release).to_chunks()
    if pending or expected != len(firsts):
        raise RuntimeError("RRD capture changed between two reads")


def _varint(data: bytes, offset: int) -> tuple[int, int]:
    value, shift = 0, 0
    while True:
        byte = data[offset]
        offset += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, offset


def _encode_varint(value: int) -> bytes:
    out = bytearray()
    while True:
        byte, value = value & 0x7F, value >> 7
        out.append(byte | (0x80 if value else 0))
        if not value:
            return bytes(out)


def _proto_fields(data: bytes) -> list[tuple[int, int | bytes]]:
    """(field number, value) of a protobuf message with varint and length-delimited fields."""
    fields, offset = [], 0
    while offset < len(data):
        tag, offset = _varint(data, offset)
        if tag & 7 == 0:
            value, offset = _varint(data, offset)
        elif tag & 7 == 2:
            length, offset = _varint(data, offset)
            value, offset = bytes(data[offset:offset + length]), offset + length
        else:
            raise RuntimeError(f"unexpected protobuf wire type {tag & 7} in RRD footer")
        fields.append((tag >> 3, value))
    if offset != len(data):
        raise RuntimeError("truncated protobuf message in RRD footer")
    return fields


def _proto_encode(fields: list[tuple[int, int | bytes]]) -> bytes:
    out = bytearray()
    for number, value in fields:
        if isinstance(value, int):
            out += _encode_varint(number << 3) + _encode_varint(value)
        else:
            out += _encode_varint(number << 3 | 2) + _encode_varint(len(value)) + value
    return bytes(out)


def _sorted_schema(schema: pa.Schema) -> pa.Schema:
    """Fields sorted by name, every metadata map sorted by key."""
    def sorted_metadata(metadata):
        return None if metadata is None else dict(sorted(metadata.items()))
    fields = [f.with_metadata(sorted_metadata(f.metadata)) if f.metadata else f
              for f in sorted(schema, key=lambda f: f.name)]
    return pa.schema(fields, metadata=sorted_metadata(schema.metadata))


def _canonical_manifest(manifest: bytes) -> bytes:
    """One footer RrdManifest with its Arrow schema and manifest table in sorted column order.

    Fields: 1 store id, 2 sorbet schema {1: Arrow IPC schema}, 3 schema sha256 (computed by
    Rerun over name-sorted fields, so already canonical), 4 manifest table {1: encoder
    version, 2: LZ4-block-compressed Arrow IPC stream, 3: compression, 4: uncompressed size}.
    """
    out = []
    for number, value in _proto_fields(manifest):
        if number == 2:
            (inner_number, schema_bytes), = _proto_fields(value)
            schema = _sorted_schema(ipc.read_schema(pa.py_buffer(schema_bytes)))
            value = _proto_encode([(inner_number, schema.serialize().to_pybytes())])
        elif number == 4:
            part = dict(_proto_fields(value))
            if part.get(3) != _LZ4_COMPRESSION:
                raise RuntimeError(f"unexpected RRD manifest compression {part.get(3)}")
            raw = _LZ4.decompress(part[2], decompressed_size=part[4])
            table = ipc.open_stream(raw).read_all()
            table = table.select(sorted(table.schema.names))
            # the same columns under the sorted metadata (Table.cast would import
            # pyarrow.compute, 25 ms, to convert nothing)
            table = pa.Table.from_arrays(table.columns, schema=_sorted_schema(table.schema))
            sink = pa.BufferOutputStream()
            with ipc.new_stream(sink, table.schema) as writer:
                writer.write_table(table)
            raw = sink.getvalue().to_pybytes()
            part[2], part[4] = _LZ4.compress(raw).to_pybytes(), len(raw)
            value = _proto_encode(sorted(part.items()))
        out.append((number, value))
    return _proto_encode(out)


def _canonical_footer(footer: bytes) -> bytes:
    """The RrdFooter protobuf with manifests sorted by store id (recording before blueprint)."""
    manifests = [value for number, value in _proto_fields(footer) if number == 1]
    if len(manifests) != len(_proto_fields(footer)):
        raise RuntimeError("unexpected field in RRD footer")
    manifests = sorted(manifests, key=lambda m: _proto_fields(m)[0][1])
    return _proto_encode([(1, _canonical_manifest(m)) for m in manifests])


def _canonical_framing(path: Path, old_blueprint_id: bytes, new_blueprint_id: bytes) -> None:
    """Patch the written file in place: counter TUIDs in SetStoreInfo envelopes, the fixed
    blueprint store id (same length as the random one) and a canonical footer."""
    if len(old_blueprint_id) != len(new_blueprint_id):
        raise ValueError("blueprint store ids must have the same length")
    with open(path, "r+b") as f:
        if f.read(4) != _RRD_MAGIC:
            raise RuntimeError(f"{path}: not an RRD stream (bad magic)")
        offset, patched = _STREAM_HEADER_BYTES, 0
        while True:
            f.seek(offset)
            header = f.read(_MESSAGE_HEADER.size)
            if len(header) < _MESSAGE_HEADER.size:
                raise RuntimeError(f"{path}: RRD stream has no End message (footer)")
            kind, length = _MESSAGE_HEADER.unpack(header)
            payload = offset + _MESSAGE_HEADER.size
            if kind == _KIND_END:
                break
            # Envelopes (store ids, row ids) sit at the start of a message payload.
            head = bytearray(f.read(min(length, _ENVELOPE_BYTES)))
            original = bytes(head)
            if kind == _KIND_SET_STORE_INFO:
                if head[:3] != _STORE_INFO_ROW_ID_PREFIX or head[11] != 0x11:
                    raise RuntimeError(f"{path}: unexpected SetStoreInfo layout")
                patched += 1
                head[3:11] = (0).to_bytes(8, "little")
                head[12:20] = patched.to_bytes(8, "little")
            head = head.replace(old_blueprint_id, new_blueprint_id)
            if head != original:
                f.seek(payload)
                f.write(head)
            offset = payload + length
        if patched == 0:
            raise RuntimeError(f"{path}: no SetStoreInfo message in RRD stream")
        footer = f.read(length)
        stream_footer = f.read()
        if len(stream_footer) != _STREAM_FOOTER.size:
            raise RuntimeError(f"{path}: unexpected RRD stream footer")
        footer_offset, footer_length, _, magic, version = _STREAM_FOOTER.unpack(stream_footer)
        if magic != _FOOTER_MAGIC or (footer_offset, footer_length) != (payload, length):
            raise RuntimeError(f"{path}: unexpected RRD stream footer")
        footer = _canonical_footer(footer.replace(old_blueprint_id, new_blueprint_id))
        crc = xxhash.xxh32(footer, seed=_FOOTER_CRC_SEED).intdigest()
        f.seek(offset)
        f.write(_MESSAGE_HEADER.pack(_KIND_END, len(footer)) + footer
                + _STREAM_FOOTER.pack(payload, len(footer), crc, magic, version))
        f.truncate()


def capture_stream(application_id: str, recording_id: str, part_path: Path,
                   blueprint: rrb.Blueprint, sinks=()) -> RecordingStream:
    """A RecordingStream without wall-clock data that saves to ``part_path`` with ``blueprint``
    and streams to ``sinks`` too (``rr.GrpcSink``, ``rr.GrpcServerSink``: a viewer watching
    while the stage runs)."""
    stream = RecordingStream(application_id, recording_id=recording_id, send_properties=False,
                             batcher_config=CAPTURE_BATCHER)
    stream.set_log_time_enabled(False)
    stream.set_log_tick_enabled(False)
    if sinks:
        stream.set_sinks(rr.FileSink(str(part_path)), *sinks, default_blueprint=blueprint)
    else:
        stream.save(part_path, default_blueprint=blueprint)
    return stream


def write_canonical_rrd(part_path: Path, rrd_path: Path, application_id: str, recording_id: str) -> None:
    """Rewrite the capture ``part_path`` as the reproducible ``rrd_path`` (see module doc)."""
    reader = RrdReader(part_path)
    chunk_ids = itertools.count(1)
    blueprint_chunks: list[Chunk] = []
    for store in reader.blueprints():
        _in_logging_order(reader, store, chunk_ids, blueprint_chunks.append)
    blueprint_stream = RecordingStream._from_native(bindings.new_blueprint(
        application_id=application_id, make_default=False, make_thread_default=False,
        default_enabled=True))
    blueprint_memory = blueprint_stream.memory_recording()
    blueprint_stream.send_chunks(blueprint_chunks)
    random_blueprint_id = blueprint_stream.get_recording_id()

    writer = RecordingStream(application_id, recording_id=recording_id, send_properties=False,
                             batcher_config=rr.ChunkBatcherConfig.NEVER())
    bindings.save(path=str(rrd_path), default_blueprint=blueprint_memory.storage,
                  recording=writer.to_native(), write_footer=True)
    for store in reader.recordings():  # none if nothing was logged
        _in_logging_order(reader, store, chunk_ids, lambda chunk: writer.send_chunks([chunk]))
    writer.flush()
    writer.disconnect()

    digest = uuid.uuid5(_BLUEPRINT_NAMESPACE, recording_id).hex * 2
    fixed_blueprint_id = ("bp_" + digest)[:len(random_blueprint_id)]
    _canonical_framing(rrd_path, random_blueprint_id.encode(), fixed_blueprint_id.encode())
