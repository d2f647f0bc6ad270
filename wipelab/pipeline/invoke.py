"""Run one pipeline stage through its own click command, in this process.

There is one code path per stage: the pipeline builds the same command line a user would
type (``learn track/track.csv -o learn --kernels 25``) and hands it to the registered click
command, so parsing, validation and defaults are the CLI's own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from wipelab.errors import InputError, from_user_interrupt
from wipelab.pipeline.spec import StageSpec, file_parameter


def stage_command(name: str) -> click.Command:
    """The registered ``wipelab NAME`` click command (imports the CLI on first use)."""
    from wipelab.cli import cli

    context = click.Context(cli)
    try:
        command = cli.get_command(context, name)
    except ImportError as error:
        raise InputError(f"wipelab {name}: not available in this installation ({error})") from None
    if command is None:
        raise InputError(f"wipelab has no command {name!r} "
                         f"(commands: {', '.join(cli.list_commands(context))})")
    return command


def build_argv(stage: StageSpec, command: click.Command, input_path: str | None,
               output_path: str, quiet: bool, source: str) -> list[str]:
    """The command line (without the program name) that runs ``stage``.

    Parameters
    ----------
    stage : StageSpec
    command : click.Command
        The stage's command; its options decide how each parameter is spelled.
    input_path : str or None
        The input argument (ignored by commands without input).
    output_path : str
        The stage folder, or the output file for commands that write one file.
    quiet : bool
        Add ``--quiet`` where the command has it.
    source : str
        The pipeline file, for error messages.
    """
    argv = [input_path] if stage.signature.takes_input else []
    argv += ["-o", output_path] if stage.signature.output_option else [output_path]
    options = [param for param in command.params if isinstance(param, click.Option)]
    for key, value in sorted(stage.parameters.items()):
        option = _option_named(options, key)
        if option is None:
            known = ", ".join(sorted(max(o.opts, key=len) for o in options
                                     if o.name not in ("help", "output", "quiet")))
            raise InputError(f"{source}: stage {stage.name}: {stage.command} has no option "
                             f"{key!r} (options: {known})")
        argv += _option_args(option, value, f"{source}: stage {stage.name}: {key}")
    quiet_option = _option_named(options, "quiet")
    if quiet and quiet_option is not None:
        argv.append(max(quiet_option.opts, key=len))
    return argv


def check_arguments(stage: StageSpec, command: click.Command, source: str) -> None:
    """Parse the stage's command line as click would, without running it.

    Catches unknown options and values of the wrong type or outside a choice (the stage
    itself still checks files and ranges when it runs).

    Raises
    ------
    InputError
        Naming the pipeline file, the stage and the problem.
    """
    from wipelab.cli.options import output_checks_deferred

    argv = build_argv(stage, command, "INPUT", stage.name, False, source)
    try:
        with output_checks_deferred():
            command.make_context(f"wipelab {command.name}", argv)
    except click.ClickException as error:
        raise InputError(f"{source}: stage {stage.name}: {_message(error)}") from None


def run_command(command: click.Command, argv: Sequence[str], stage_name: str,
                source: str) -> None:
    """Run a click command in-process, as ``wipelab <command> ARGV`` would.

    Raises
    ------
    InputError
        The stage's own InputError, or click's usage error, prefixed with the stage.
    RuntimeError
        The command exited with a non-zero code.
    """
    try:
        code = command.main(args=list(argv), prog_name=f"wipelab {command.name}",
                            standalone_mode=False)
    except InputError as error:
        raise InputError(f"stage {stage_name}: {error}") from None
    except click.exceptions.Abort:
        raise KeyboardInterrupt from None
    except SystemError as error:
        if from_user_interrupt(error):
            raise KeyboardInterrupt from None
        raise
    except click.ClickException as error:
        raise InputError(f"{source}: stage {stage_name}: {_message(error)}") from None
    if isinstance(code, int) and code != 0:
        raise RuntimeError(f"stage {stage_name}: wipelab {command.name} exited with code {code}")


def _message(error: click.ClickException) -> str:
    from wipelab.cli.usage_errors import usage_message

    return usage_message(error) if isinstance(error, click.UsageError) else error.format_message()


def _option_named(options: list[click.Option], key: str) -> click.Option | None:
    """The option spelled ``--key`` (``frequency_scale`` matches ``--frequency-scale``)."""
    flag = "--" + key.replace("_", "-")
    for option in options:
        if flag in option.opts or flag in option.secondary_opts:
            return option
    return None


def _option_args(option: click.Option, value: Any, where: str) -> list[str]:
    flag = max(option.opts, key=len)
    if option.is_flag:
        if not isinstance(value, bool):
            raise InputError(f"{where}: {flag} is a flag, give true or false")
        if value == bool(option.flag_value):
            return [flag]
        return [max(option.secondary_opts, key=len)] if option.secondary_opts else []
    values = value if isinstance(value, list) else [value]
    if option.multiple:
        return [arg for v in values for arg in (flag, _text(v))]
    if option.nargs > 1:
        if len(values) != option.nargs:
            raise InputError(f"{where}: {flag} takes {option.nargs} values, got {len(values)}")
        return [flag, *map(_text, values)]
    return [flag, ",".join(map(_text, values))]


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    path = file_parameter(value)
    return str(value) if path is None else str(path)
