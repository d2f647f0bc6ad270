"""Pipeline files: which stages run in which order, with which parameters and inputs.

A pipeline is a TOML file::

    [pipeline]
    name = "quickstart"
    description = "The bundled demo end to end."

    [inputs]                      # named external inputs, paths relative to this file;
    demo = "../data/demo"         # `wipelab run --input demo=DIR` replaces one

    [stages.track]                # a stage: its folder under the run directory is "track"
    command = "track"             # the wipelab command it runs (default: the stage name)
    input = "demo"                # an [inputs] name (or "NAME:FILE", a file in it), "STAGE:FILE",
                                  # or a path relative to this file
    particles = 300               # every other key is an option of the command: --particles 300

    [stages.learn]
    input = "track:track.csv"     # the file track.csv that stage "track" wrote

Stages run in the order they are written. A list value becomes a repeated option when the
command's option takes several values (``--frequency-scale 1 --frequency-scale 2``) and a
comma-joined one otherwise (``--dofs x,y``); ``true`` turns a flag on. A file given to an
option is written ``{ file = "surfaces/wavy.toml" }`` (relative to this file): the stage gets
its absolute path, and its content, with the files beside it, is part of the cache key.
"""

from __future__ import annotations

import os
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from wipelab.errors import InputError
from wipelab.input_files import read_input_toml

@dataclass(frozen=True)
class CommandSignature:
    """How a stage command takes its input and writes its output (DESIGN.md, "Stages and
    external contract")."""

    takes_input: bool        # the first positional argument is the stage's input path
    output_option: bool      # output given as ``-o OUT`` (False: as the positional OUT_DIR)
    output_file: str | None  # the default file name when the output is one file, else None


STAGE_COMMANDS: Mapping[str, CommandSignature] = {
    "synth": CommandSignature(takes_input=False, output_option=False, output_file=None),
    "track": CommandSignature(takes_input=True, output_option=True, output_file=None),
    "learn": CommandSignature(takes_input=True, output_option=True, output_file=None),
    "rollout": CommandSignature(takes_input=True, output_option=True, output_file="rollout.csv"),
    "adapt": CommandSignature(takes_input=True, output_option=True, output_file=None),
    "replay": CommandSignature(takes_input=True, output_option=True, output_file=None),
}

#: Folder of the run directory where ``wipelab report`` writes; no stage may take its name.
REPORT_DIR = "report"

#: Keys of a stage table that are not command options.
STAGE_KEYS = ("command", "input", "output")

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")

Scalar = str | int | float | bool


@dataclass(frozen=True)
class StageSpec:
    """One stage of a pipeline.

    Attributes
    ----------
    name : str
        Unique name; the stage writes into ``RUN_DIR/<name>/``.
    command : str
        The wipelab command it runs, a key of :data:`STAGE_COMMANDS`.
    input : str or None
        Reference to its input (see :meth:`Pipeline.resolve_input`); None for ``synth``.
    output : str or None
        File name of the output inside the stage folder, for commands that write one file.
    parameters : dict[str, scalar, list of scalars or {"file": absolute path}]
        Command options by name (``frequency_scale`` or ``frequency-scale``).
    """

    name: str
    command: str
    input: str | None
    output: str | None
    parameters: Mapping[str, Any] = field(default_factory=dict)

    @property
    def signature(self) -> CommandSignature:
        return STAGE_COMMANDS[self.command]


@dataclass(frozen=True)
class Pipeline:
    """A parsed pipeline file.

    Attributes
    ----------
    source : str
        The file it came from, for error messages.
    base_dir : Path
        Directory that relative paths in the file are relative to.
    name, description : str
    inputs : dict[str, Path]
        Named external inputs, absolute.
    stages : tuple of StageSpec
        In execution order.
    """

    source: str
    base_dir: Path
    name: str
    description: str
    inputs: Mapping[str, Path]
    stages: tuple[StageSpec, ...]

    def stage(self, name: str) -> StageSpec:
        for stage in self.stages:
            if stage.name == name:
                return stage
        raise InputError(f"{self.source}: no stage named {name!r} "
                         f"(stages: {', '.join(s.name for s in self.stages)})")

    def resolve_input(self, stage: StageSpec, run_dir: Path) -> Path | None:
        """The path a stage reads: a named input, another stage's file, or a plain path.

        ``"demo"`` (a key of ``[inputs]``) is that input and ``"demo:truth.csv"`` a file in
        it; ``"learn:model.json"`` is the file ``model.json`` in ``run_dir/learn``; anything
        else is a path relative to the pipeline file's directory.
        """
        if stage.input is None:
            return None
        if stage.input in self.inputs:
            return self.inputs[stage.input]
        producer, file_name = _split_stage_reference(stage.input)
        if producer in self.inputs:
            return self.inputs[producer] / file_name
        if producer is not None:
            return run_dir / producer / file_name
        return self.base_dir / stage.input

    def upstream(self, stage: StageSpec) -> str | None:
        """Name of the stage whose output ``stage`` reads, or None for an external input."""
        if stage.input is None or stage.input in self.inputs:
            return None
        producer = _split_stage_reference(stage.input)[0]
        return None if producer in self.inputs else producer

    def with_overrides(self, sets: Sequence[str] = (),
                       inputs: Sequence[str] = ()) -> Pipeline:
        """A copy with ``--set stage.key=value`` and ``--input name=path`` applied.

        Values are read as TOML values where they parse (``30``, ``1.5``, ``true``,
        ``["x", "y"]``) and as plain strings otherwise (``bowl``). Paths given in ``inputs``
        are relative to the current directory.
        """
        named = dict(self.inputs)
        for item in inputs:
            key, sep, value = item.partition("=")
            if not sep:
                if len(named) != 1:
                    raise InputError(f"--input {item}: the pipeline has {len(named)} inputs, "
                                     f"say which one: --input NAME=PATH")
                key, value = next(iter(named)), item
            if key not in named:
                raise InputError(f"--input {item}: the pipeline has no input {key!r} "
                                 f"(inputs: {', '.join(named) or 'none'})")
            named[key] = Path(value).resolve()
        stages = {stage.name: stage for stage in self.stages}
        for item in sets:
            path, sep, value = item.partition("=")
            stage_name, _, key = path.strip().partition(".")
            if not sep or not stage_name or not key:
                raise InputError(f"--set {item}: expected STAGE.KEY=VALUE")
            stage = stages.get(stage_name)
            if stage is None:
                raise InputError(f"--set {item}: no stage named {stage_name!r} "
                                 f"(stages: {', '.join(stages)})")
            parsed = _parse_value(value.strip())
            if key == "command":
                raise InputError(f"--set {item}: a stage's command cannot be overridden")
            if key in ("input", "output"):
                stage = replace(stage, **{key: str(parsed)})
            else:
                parsed = _resolve_files({key: parsed}, Path.cwd())[key]
                stage = replace(stage, parameters={**stage.parameters, key: parsed})
            stages[stage_name] = stage
        overridden = replace(self, inputs=named, stages=tuple(stages.values()))
        overridden._check_references()
        for stage in overridden.stages:
            _check_parameters(overridden.source, stage)
        return overridden

    def _check_references(self) -> None:
        seen: list[str] = []
        for stage in self.stages:
            producer = self.upstream(stage)
            if producer is not None and producer not in seen:
                where = "a later stage" if producer in {s.name for s in self.stages} else \
                    "no stage"
                raise InputError(f"{self.source}: stage {stage.name}: input {stage.input!r} "
                                 f"names {where} ({producer!r}); a stage reads from the "
                                 f"stages before it")
            seen.append(stage.name)


def load_pipeline(path: str | os.PathLike) -> Pipeline:
    """Read and validate a pipeline TOML file (see the module docstring for the format).

    Raises
    ------
    InputError
        Naming the file: missing, not TOML, unknown keys or commands, bad names, a stage input
        that names a later stage, option values that are not scalars or lists of scalars.
    """
    path = Path(path)
    source = str(path)
    data = read_input_toml(path)
    unknown = sorted(set(data) - {"pipeline", "inputs", "stages"})
    if unknown:
        raise InputError(f"{source}: unknown table(s) {', '.join(unknown)} "
                         f"(expected pipeline, inputs, stages)")
    header = _table(data.get("pipeline", {}), source, "[pipeline]")
    base_dir = path.resolve().parent
    inputs = {}
    for key, value in _table(data.get("inputs", {}), source, "[inputs]").items():
        if not isinstance(value, str):
            raise InputError(f"{source}: [inputs] {key} must be a path string")
        inputs[_checked_name(key, source, "input")] = (base_dir / value).resolve()
    stage_tables = _table(data.get("stages", {}), source, "[stages]")
    if not stage_tables:
        raise InputError(f"{source}: no stages (add a [stages.NAME] table)")
    stages = []
    for name, table in stage_tables.items():
        table = _table(table, source, f"[stages.{name}]")
        stage = _stage_from_table(_checked_name(name, source, "stage"), table, source, base_dir)
        if stage.name in inputs or stage.name == REPORT_DIR:
            raise InputError(f"{source}: stage {name!r}: name taken (by an input or by "
                             f"RUN_DIR/{REPORT_DIR}, where `wipelab report` writes)")
        stages.append(stage)
    pipeline = Pipeline(source=source, base_dir=base_dir,
                        name=str(header.get("name", path.stem)),
                        description=str(header.get("description", "")),
                        inputs=inputs, stages=tuple(stages))
    pipeline._check_references()
    return pipeline


def file_parameter(value: Any) -> Path | None:
    """The path of a ``{ file = "..." }`` parameter value (absolute once loaded), else None."""
    if isinstance(value, dict) and set(value) == {"file"} and isinstance(value["file"], str):
        return Path(value["file"])
    return None


def _resolve_files(parameters: Mapping[str, Any], base_dir: Path) -> dict[str, Any]:
    return {key: {"file": str((base_dir / path).resolve())}
            if (path := file_parameter(value)) is not None else value
            for key, value in parameters.items()}


def _stage_from_table(name: str, table: Mapping[str, Any], source: str,
                      base_dir: Path) -> StageSpec:
    command = table.get("command", name)
    if command not in STAGE_COMMANDS:
        raise InputError(f"{source}: stage {name}: unknown command {command!r} "
                         f"(one of {', '.join(STAGE_COMMANDS)})")
    signature = STAGE_COMMANDS[command]
    stage_input = table.get("input")
    if signature.takes_input and not isinstance(stage_input, str):
        raise InputError(f"{source}: stage {name}: {command} needs input = \"...\" "
                         f"(an input name, STAGE:FILE or a path)")
    if not signature.takes_input and stage_input is not None:
        raise InputError(f"{source}: stage {name}: {command} takes no input")
    output = table.get("output", signature.output_file)
    if output is not None and (signature.output_file is None or not isinstance(output, str)
                               or Path(output).name != output):
        raise InputError(f"{source}: stage {name}: output must be a plain file name and only "
                         f"for commands that write one file (rollout)")
    parameters = _resolve_files({key: value for key, value in table.items()
                                 if key not in STAGE_KEYS}, base_dir)
    stage = StageSpec(name=name, command=command, input=stage_input, output=output,
                      parameters=parameters)
    _check_parameters(source, stage)
    return stage


def _check_parameters(source: str, stage: StageSpec) -> None:
    for key, value in stage.parameters.items():
        if key in ("o", "output", "quiet", "help"):
            raise InputError(f"{source}: stage {stage.name}: {key!r} is set by the pipeline "
                             f"runner, not by the pipeline file")
        values = value if isinstance(value, list) else [value]
        if file_parameter(value) is None and (
                not values or not all(isinstance(v, Scalar) for v in values)):
            raise InputError(f"{source}: stage {stage.name}: {key} must be a string, number, "
                             f"boolean, a non-empty list of them or {{ file = \"PATH\" }}")


def _split_stage_reference(reference: str) -> tuple[str | None, str]:
    producer, sep, file_name = reference.partition(":")
    if sep and _NAME.match(producer) and file_name and Path(file_name).name == file_name:
        return producer, file_name
    return None, reference


def _table(value: Any, source: str, what: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise InputError(f"{source}: {what} must be a table")
    return value


def _checked_name(name: str, source: str, what: str) -> str:
    if not _NAME.match(name):
        raise InputError(f"{source}: bad {what} name {name!r} (letters, digits, _ and -, "
                         f"starting with a letter)")
    return name


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        return text
