"""The stage cache: content hashes, the cache key of a stage run, and its record on disk.

Like DVC's run cache, a stage's key is a hash of what can change its outputs: the stage
name, its command, wipelab's version, its sorted parameters and the content hashes of its
inputs. The code is a dependency like the inputs: the record lists every wipelab source file
that was loaded when the stage ran (and the package's data files, e.g. the robot model) with
its hash, so editing the simulator reruns adapt but not track. After a stage succeeds the
runner writes ``RUN_DIR/<stage>/.wipelab-stage.json`` with the key, those code hashes and the
hashes of every file the stage wrote, last and atomically. The stage is reused while the key
is unchanged, its code files are unchanged and every recorded output is still there with its
recorded hash: "the output exists" alone is never "up to date".

Only the standard library is imported here, so that a fully cached run starts fast.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import wipelab

#: Name of the record a finished stage leaves in its folder.
RECORD_NAME = ".wipelab-stage.json"

#: ``format`` field of the record; a record of another format is treated as absent.
RECORD_FORMAT = "wipelab.stage_cache/1"


def sha256_of_file(path: Path) -> str:
    """Hex SHA-256 of a file, read in large blocks (about 1.5 GB/s here)."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def files_under(root: Path) -> list[Path]:
    """Every regular file under ``root`` except hidden ones and the stage record, sorted.

    Hidden names (``.``-prefixed: the record, temporary files of a writer) are not content.
    """
    files = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if not d.startswith(".") and d != "__pycache__")
        files.extend(Path(dirpath) / name for name in filenames if not name.startswith("."))
    return sorted(files)


class DigestMemo:
    """Content hashes of files, each file read at most once while its size and mtime hold.

    One memo lives for one pipeline run: a stage's outputs are hashed when they are checked
    or recorded and that hash serves again when the next stage reads them.
    """

    def __init__(self) -> None:
        self._digests: dict[Path, tuple[int, int, str]] = {}

    def file(self, path: Path) -> str:
        """Hex SHA-256 of one file."""
        stat = path.stat()
        known = self._digests.get(path)
        if known is not None and known[:2] == (stat.st_size, stat.st_mtime_ns):
            return known[2]
        digest = sha256_of_file(path)
        self._digests[path] = (stat.st_size, stat.st_mtime_ns, digest)
        return digest

    def files(self, root: Path) -> dict[str, str]:
        """``{relative posix path: sha256}`` of :func:`files_under` ``root``."""
        return {path.relative_to(root).as_posix(): self.file(path) for path in files_under(root)}

    def content(self, path: Path) -> str:
        """One hash of a file's bytes, or of a directory's file names and bytes."""
        if path.is_dir():
            return _hash_json(self.files(path))
        return self.file(path)


def package_root() -> Path:
    """The directory of the installed ``wipelab`` package."""
    return Path(wipelab.__file__).parent


def code_files_in_use() -> list[str]:
    """Package files a stage that just ran may depend on, relative to :func:`package_root`.

    Every loaded ``wipelab`` module (a stage imports what it uses, lazily or not) and every
    data file of the package (read at run time, e.g. the robot's URDF and meshes). A
    superset of a stage's real dependencies when several stages run in one process, never
    a subset.
    """
    root = package_root()
    files = {path for path in files_under(root) if path.suffix not in (".py", ".pyc", ".pyo")}
    for name, module in list(sys.modules.items()):
        path = getattr(module, "__file__", None)
        if (name == "wipelab" or name.startswith("wipelab.")) and path:
            files.add(Path(path))
    # A module's file can be gone while the module stays loaded (the source was removed
    # after import): what is not on disk cannot be checked later, so it is not recorded.
    return sorted(p.relative_to(root).as_posix() for p in files
                  if p.is_relative_to(root) and p.is_file())


def stage_key(stage: str, command: str, version: str, parameters: dict[str, Any],
              output: str | None, input_digest: str | None) -> str:
    """The cache key of a stage run: a hash of its definition and its inputs' content."""
    return _hash_json({"stage": stage, "command": command, "version": version,
                       "parameters": parameters, "output": output, "input": input_digest})


@dataclass(frozen=True)
class StageRecord:
    """What a finished stage left: its key, how it was made, its outputs' hashes.

    Attributes
    ----------
    key : str
        :func:`stage_key` of the run.
    stage, command : str
    code : dict[str, str]
        ``{path relative to the package: sha256}`` of :func:`code_files_in_use`.
    parameters : dict
        The options it ran with, as in the pipeline file.
    input : str or None
        The input as passed to the command (relative to the run directory where it is
        inside it).
    input_digest : str or None
        Content hash of the input.
    outputs : dict[str, str]
        ``{path relative to the stage folder: sha256}`` of every file the stage wrote.
    seconds : float
        Wall time of the run that made it.
    """

    key: str
    stage: str
    command: str
    code: dict[str, str]
    parameters: dict[str, Any]
    input: str | None
    input_digest: str | None
    outputs: dict[str, str]
    seconds: float

    def code_intact(self, memo: DigestMemo) -> bool:
        """True when every code file the stage ran with is unchanged."""
        root = package_root()
        try:
            return all(memo.file(root / name) == digest for name, digest in self.code.items())
        except OSError:
            return False

    def outputs_intact(self, stage_dir: Path, memo: DigestMemo) -> bool:
        """True when ``stage_dir`` holds exactly the recorded files with the recorded hashes."""
        try:
            return memo.files(stage_dir) == self.outputs
        except OSError:
            return False


def read_record(stage_dir: Path) -> StageRecord | None:
    """The record in ``stage_dir``, or None when absent, unreadable or of another format."""
    try:
        data = json.loads((stage_dir / RECORD_NAME).read_text())
        if data.pop("format") != RECORD_FORMAT:
            return None
        return StageRecord(**data)
    except (OSError, ValueError, TypeError, KeyError):
        return None


def write_record(stage_dir: Path, record: StageRecord) -> None:
    """Write the record atomically (temporary name, fsync, rename): it is the commit point."""
    target = stage_dir / RECORD_NAME
    tmp = stage_dir / f"{RECORD_NAME}.partial-{os.getpid()}"
    text = json.dumps({"format": RECORD_FORMAT, **asdict(record)}, indent=2, sort_keys=True)
    try:
        with open(tmp, "w") as f:
            f.write(text + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def remove_record(stage_dir: Path) -> None:
    """Invalidate a stage before it is rerun, so that an interrupted rerun is never reused."""
    (stage_dir / RECORD_NAME).unlink(missing_ok=True)


def _hash_json(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()
