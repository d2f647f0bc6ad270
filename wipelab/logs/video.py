"""Video files as per-frame access units, for ``foxglove.CompressedVideo``.

Foxglove plays H.264/H.265 as Annex B byte streams and AV1 as OBUs, one message per frame,
without B-frames. MP4 stores H.264/H.265 length-prefixed with the parameter sets in the
container header; FFmpeg's ``*_mp4toannexb`` bitstream filters (through PyAV) rewrite each
sample to Annex B and put the parameter sets in front of every key frame.
"""

from __future__ import annotations

import os
from typing import Iterator

from wipelab.errors import InputError

# PyAV is imported where it is used: 0.1-0.2 s at start-up, and only track logs video.

#: FFmpeg codec name -> (Foxglove CompressedVideo ``format``, bitstream filter or None).
VIDEO_CODECS = {"h264": ("h264", "h264_mp4toannexb"), "hevc": ("h265", "hevc_mp4toannexb"),
                "av1": ("av1", None)}


def video_codec(path: str | os.PathLike) -> str:
    """FFmpeg name of the codec of the first video stream of ``path`` ("h264", "mpeg4", ...)."""
    import av

    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise InputError(f"{path}: has no video stream")
            return container.streams.video[0].codec_context.name
    except av.error.FFmpegError as exc:
        raise InputError(f"{path}: cannot be read as video ({exc})") from exc


def access_units(path: str | os.PathLike) -> tuple[str, Iterator[bytes]]:
    """Foxglove ``format`` and an iterator over the frames' access units in presentation order.

    Raises
    ------
    InputError
        If the codec is not H.264, H.265 or AV1, or the stream has B-frames (decode order
        differs from presentation order).
    """
    codec = video_codec(path)
    if codec not in VIDEO_CODECS:
        raise InputError(f"{path}: video codec {codec!r} cannot be logged as video "
                         f"(H.264, H.265 or AV1 needed; Rerun and Foxglove decode only those)")
    foxglove_format, filter_name = VIDEO_CODECS[codec]

    def units() -> Iterator[bytes]:
        import av
        from av.bitstream import BitStreamFilterContext

        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            bitstream_filter = BitStreamFilterContext(filter_name, stream) if filter_name else None
            last_pts = None
            packets = (p for p in container.demux(stream) if p.size)
            for packet in packets:
                for out in bitstream_filter.filter(packet) if bitstream_filter else [packet]:
                    if last_pts is not None and out.pts is not None and out.pts <= last_pts:
                        raise InputError(f"{path}: has B-frames (frames out of presentation order); "
                                         f"encode without them (e.g. x264 bf=0)")
                    last_pts = out.pts
                    yield bytes(out)
            if bitstream_filter:
                for out in bitstream_filter.filter(None):
                    yield bytes(out)

    return foxglove_format, units()
