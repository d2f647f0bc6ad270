"""One stage's MCAP file: ZSTD chunks, full index, named schemas, data-time stamps.

A thin layer over :class:`mcap.writer.Writer` that owns the schema and channel registry so
callers write ``(topic, log_time_ns, message)`` and nothing else. Two kinds of channel:

* protobuf channels with a Foxglove well-known schema (``foxglove.CompressedImage``, ...),
  message encoding ``protobuf``;
* JSON channels with a named JSON Schema (schema encoding ``jsonschema``, message
  encoding ``json``).

``publish_time`` equals ``log_time`` (data time); ``sequence`` counts per channel from 0.
Attachments get ``log_time = create_time = 0``. Nothing depends on the wall clock, so equal
calls give equal bytes.
"""

from __future__ import annotations

import json
import math
from contextlib import contextmanager
from typing import Any, BinaryIO, Iterator

from mcap.writer import CompressionType, IndexType, Writer

import wipelab

JSON = "json"
JSONSCHEMA = "jsonschema"

#: MCAP header ``library`` field.
LIBRARY = f"wipelab {wipelab.__version__}"


def json_ready(value: Any) -> Any:
    """``value`` with numpy arrays/scalars as lists/numbers and non-finite floats as None.

    JSON has no NaN or infinity; a missing value (e.g. an invalid tracking sample) is ``null``.
    """
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if hasattr(value, "tolist"):  # numpy array or scalar
        return json_ready(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_bytes(value: Any) -> bytes:
    """Canonical JSON (sorted keys, no spaces, UTF-8) of ``json_ready(value)``."""
    return json.dumps(json_ready(value), sort_keys=True, separators=(",", ":"),
                      allow_nan=False, ensure_ascii=False).encode()


class McapLog:
    """Writer of one MCAP file.

    Parameters
    ----------
    stream : binary file object opened for writing.
    chunk_size : int
        Uncompressed bytes per chunk before it is compressed and written.
    """

    def __init__(self, stream: BinaryIO, chunk_size: int = 1 << 20):
        self._writer = Writer(stream, chunk_size=chunk_size, compression=CompressionType.ZSTD,
                              index_types=IndexType.ALL, repeat_channels=True, repeat_schemas=True,
                              use_chunking=True, use_statistics=True, use_summary_offsets=True,
                              enable_crcs=True, enable_data_crcs=True)
        self._writer.start(profile="", library=LIBRARY)
        self._schemas: dict[tuple[str, str, bytes], int] = {}
        self._channels: dict[str, tuple[int, str, int]] = {}  # topic -> (channel id, encoding, schema id)
        self._sequence: dict[int, int] = {}
        self._held: list[tuple[int, int, bytes]] | None = None
        self._finished = False

    def _schema_id(self, name: str, encoding: str, data: bytes) -> int:
        key = (name, encoding, data)
        if key not in self._schemas:
            self._schemas[key] = self._writer.register_schema(name=name, encoding=encoding, data=data)
        return self._schemas[key]

    def channel(self, topic: str, message_encoding: str, schema_name: str, schema_encoding: str,
                schema_data: bytes) -> int:
        """Channel id of ``topic``, registering it on first use.

        Raises
        ------
        ValueError
            If ``topic`` was registered before with another schema or encoding.
        """
        schema_id = self._schema_id(schema_name, schema_encoding, schema_data)
        known = self._channels.get(topic)
        if known is None:
            channel_id = self._writer.register_channel(topic=topic, message_encoding=message_encoding,
                                                       schema_id=schema_id)
            self._channels[topic] = (channel_id, message_encoding, schema_id)
            self._sequence[channel_id] = 0
            return channel_id
        channel_id, encoding, known_schema = known
        if (encoding, known_schema) != (message_encoding, schema_id):
            raise ValueError(f"MCAP topic {topic!r} already carries another schema or encoding "
                             f"(schema {schema_name!r}, encoding {message_encoding!r} requested)")
        return channel_id

    def protobuf_channel(self, topic: str, message_type) -> int:
        """Channel for a ``foxglove.messages`` type, schema under its exact Foxglove name."""
        schema = message_type.get_schema()
        return self.channel(topic, "protobuf", schema.name, schema.encoding, bytes(schema.data))

    def json_channel(self, topic: str, schema_name: str, schema: dict) -> int:
        """Channel with a named JSON Schema (schema encoding jsonschema, message encoding json)."""
        return self.channel(topic, JSON, schema_name, JSONSCHEMA, json_bytes(schema))

    def write(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        """One message at data time ``log_time_ns`` (also its publish time)."""
        if self._held is not None:
            self._held.append((channel_id, log_time_ns, data))
            return
        sequence = self._sequence[channel_id]
        self._sequence[channel_id] = sequence + 1
        self._writer.add_message(channel_id=channel_id, log_time=log_time_ns, data=data,
                                 publish_time=log_time_ns, sequence=sequence)

    @contextmanager
    def in_time_order(self) -> Iterator[None]:
        """Hold the messages written in the block and write them when it ends, in log-time
        order; messages of equal times keep the order they were written in. Series written
        one after the other (each over all its times) so come out in the file as if they
        had been written time by time."""
        if self._held is not None:
            raise RuntimeError("in_time_order blocks do not nest")
        self._held = []
        try:
            yield
        finally:
            held, self._held = self._held, None
            held.sort(key=lambda message: message[1])
            for channel_id, log_time_ns, data in held:
                self.write(channel_id, log_time_ns, data)

    def metadata(self, name: str, values: dict[str, str]) -> None:
        self._writer.add_metadata(name=name, data={str(k): str(v) for k, v in values.items()})

    def attachment(self, name: str, data: bytes, media_type: str) -> None:
        self._writer.add_attachment(create_time=0, log_time=0, name=name, media_type=media_type,
                                    data=data)

    def finish(self) -> None:
        """Write the summary, summary offsets and footer (idempotent)."""
        if not self._finished:
            self._finished = True
            self._writer.finish()
