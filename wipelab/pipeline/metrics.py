"""The numbers a run produced: every stage's ``metrics.json`` and the learned frequency; and
the truth a synthetic demo was rendered with.

Used by the data set summary table and the report. Keys are ``<stage>.<name>``, nested
objects are joined with dots (``adapt.force.rms_error_n``); only finite numbers are kept.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from wipelab.errors import InputError
from wipelab.input_files import read_input_json, read_input_toml
from wipelab.pipeline.cache import read_record

#: Per-stage files whose numbers are collected, and the keys taken from each
#: (None: every number in the file).
METRIC_FILES: dict[str, tuple[str, ...] | None] = {
    "metrics.json": None,
    "model.json": ("frequency_hz",),
}


#: The metrics that say most (globs over ``<stage>.<key>``): the learned frequency, the
#: learned height and force errors with the learned profile, and the force error of the
#: replay with learned profile and compliance at each frequency scale.
KEY_METRICS = ("*.frequency_hz", "*.profile_hold.rms_height_error_m",
               "*.force_hold.rms_force_error_n",
               "*.scales.*.learned+compliance.rms_force_error_n")


def is_key_metric(name: str, patterns: Sequence[str] = KEY_METRICS) -> bool:
    """True when ``name`` matches one of ``patterns`` (shell-style globs)."""
    return any(fnmatch.fnmatchcase(name, pattern) for pattern in patterns)


def synthetic_frequency_hz(demo_dir: str | Path) -> float | None:
    """The wiping frequency a synthetic demo was rendered at (``[synth] frequency_hz`` of its
    demo.toml), or None for a recorded demo (or an unreadable demo.toml)."""
    try:
        synth = read_input_toml(Path(demo_dir) / "demo.toml").get("synth", {})
    except InputError:
        return None
    value = synth.get("frequency_hz") if isinstance(synth, dict) else None
    return float(value) if isinstance(value, (int, float)) else None


def demo_metrics(demo_dir: str | Path) -> dict[str, float]:
    """``{"demo.frequency_hz": f}`` for a synthetic demo (beside the learned one in the data
    set summary), ``{}`` for a recorded one."""
    frequency_hz = synthetic_frequency_hz(demo_dir)
    return {} if frequency_hz is None else {"demo.frequency_hz": frequency_hz}


def run_metrics(run_dir: str | Path) -> dict[str, float]:
    """Metrics of every finished stage in ``run_dir`` (stages without a record are skipped).

    Returns
    -------
    dict[str, float]
        ``{"<stage>.<key>": value}``, sorted by key.
    """
    run_dir = Path(run_dir)
    metrics: dict[str, float] = {}
    for stage_dir in sorted(p for p in run_dir.iterdir() if p.is_dir()):
        if read_record(stage_dir) is None:
            continue
        for file_name, keys in METRIC_FILES.items():
            path = stage_dir / file_name
            if not path.is_file():
                continue
            data = read_input_json(path)
            if keys is not None:
                data = {key: data[key] for key in keys if key in data} \
                    if isinstance(data, dict) else {}
            metrics.update(flatten_numbers(data, prefix=stage_dir.name))
    return dict(sorted(metrics.items()))


def flatten_numbers(data: Any, prefix: str) -> dict[str, float]:
    """``{"a": {"b": 1.5}, "c": "x"}`` -> ``{"<prefix>.a.b": 1.5}``: finite numbers only.

    Lists of numbers get their index in the key (``replay.scale.0``).
    """
    if isinstance(data, bool):
        return {}
    if isinstance(data, int | float):
        return {prefix: float(data)} if math.isfinite(data) else {}
    items: Any = ()
    if isinstance(data, dict):
        items = data.items()
    elif isinstance(data, list):
        items = enumerate(data)
    flat: dict[str, float] = {}
    for key, value in items:
        flat.update(flatten_numbers(value, f"{prefix}.{key}"))
    return flat
