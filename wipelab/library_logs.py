"""Keep the log lines of C libraries (OpenCV, FFmpeg) off wipelab's stderr.

A garbage video makes FFmpeg print ``[mov,mp4,... @ 0x...] moov atom not found`` and OpenCV
``[ WARN:0@0.5] global cap.cpp:212 open VIDEOIO(FFMPEG): ...`` before wipelab's own one-line
error says the same in words. Both libraries read their log level from the environment when
they start up, so it is set before any of them is imported (``wipelab -v`` leaves it alone).
"""

from __future__ import annotations

import os

#: Environment variables that silence the libraries; a value the user set is kept.
QUIET_ENVIRONMENT = {
    "OPENCV_LOG_LEVEL": "SILENT",      # OpenCV's own warnings
    "OPENCV_FFMPEG_LOGLEVEL": "-8",    # AV_LOG_QUIET for the FFmpeg inside OpenCV's videoio
}


def silence_library_logs() -> None:
    """Set :data:`QUIET_ENVIRONMENT` (inherited by the stage processes started later)."""
    for name, value in QUIET_ENVIRONMENT.items():
        os.environ.setdefault(name, value)
