"""``manifest.json``: what a stage run read, with which parameters and software."""

from __future__ import annotations

import hashlib
import json
import os
import platform
from importlib import metadata
from pathlib import Path
from typing import Any

import wipelab

#: Packages whose versions can change a stage's output; recorded in every manifest.
TRACKED_PACKAGES = (
    "numpy", "scipy", "opencv-python-headless", "rerun-sdk", "mcap", "foxglove-sdk",
    "pybullet", "click",
)


def sha256_file(path: str | os.PathLike, chunk_bytes: int = 1 << 20) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk_bytes):
            digest.update(block)
    return digest.hexdigest()


def package_versions() -> dict[str, str]:
    """Installed versions of the packages in ``TRACKED_PACKAGES`` (absent ones omitted)."""
    versions = {"wipelab": wipelab.__version__, "python": platform.python_version()}
    for name in TRACKED_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return versions


def build_manifest(stage: str, inputs: dict[str, str | os.PathLike], parameters: dict[str, Any],
                   seed: int | None = None,
                   input_hashes: dict[str, str] | None = None) -> dict[str, Any]:
    """The manifest of one stage run.

    ``inputs`` maps a role ("trajectory", "left_video", ...) to a file; each is recorded with
    its path as given and its sha256 (from ``input_hashes``, role -> sha256, where the stage
    hashed it already, e.g. :attr:`wipelab.logs.StageRecorder.input_hashes`). ``parameters``
    must be JSON-serialisable.
    """
    known = input_hashes or {}
    return {
        "format": "wipelab.manifest/1",
        "stage": stage,
        "inputs": {role: {"path": str(path), "sha256": known.get(role) or sha256_file(path)}
                   for role, path in sorted(inputs.items())},
        "parameters": parameters,
        "seed": seed,
        "versions": package_versions(),
    }


def write_json(path: str | os.PathLike, data: Any) -> None:
    """Write JSON deterministically: sorted keys, two-space indent, trailing newline."""
    Path(path).write_text(json.dumps(data, indent=2, sort_keys=True) + "\n")
