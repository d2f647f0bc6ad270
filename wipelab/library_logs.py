"""Keep the log lines of the libraries wipelab uses off its stderr.

A garbage video makes FFmpeg print ``[mov,mp4,... @ 0x...] moov atom not found`` and OpenCV
``[ WARN:0@0.5] global cap.cpp:212 open VIDEOIO(FFMPEG): ...``, a cut-short recording makes
Rerun warn about its format, all before wipelab's own one-line error says the same in
words. OpenCV and FFmpeg read their log level from the environment when they start up, so
it is set before any of them is imported; Python warnings are shown only when wipelab's own
code raises them. ``wipelab -v`` leaves all of it alone.
"""

from __future__ import annotations

import os
import warnings

#: Environment variables that silence the C libraries; a value the user set is kept.
QUIET_ENVIRONMENT = {
    "OPENCV_LOG_LEVEL": "SILENT",      # OpenCV's own warnings
    "OPENCV_FFMPEG_LOGLEVEL": "-8",    # AV_LOG_QUIET for the FFmpeg inside OpenCV's videoio
}


def silence_library_logs() -> None:
    """Set :data:`QUIET_ENVIRONMENT` (inherited by the processes started later) and ignore
    the Python warnings of other packages."""
    for name, value in QUIET_ENVIRONMENT.items():
        os.environ.setdefault(name, value)
    warnings.filterwarnings("ignore")
    warnings.filterwarnings("default", module=r"wipelab(\.|$)")
