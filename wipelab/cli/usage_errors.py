"""click's usage errors in wipelab's one-line form ``<option or argument>: <what is wrong>``.

click reports a bad option as three lines (usage, a hint, ``Error: Invalid value for
'--particles': ...``); wipelab's contract is one line ``error: <option>: <what>``, the same
as for its own :class:`~wipelab.errors.InputError`. :func:`usage_message` makes that line's
text; the command group (:mod:`wipelab.cli`) and the pipeline runner both use it.
"""

from __future__ import annotations

import difflib
import re

import click


def usage_message(error: click.UsageError) -> str:
    """``"<option or argument>: <what is wrong>"`` for one of click's usage errors.

    Examples: ``--particles: -5 is not in the range 10<=x<=5000``,
    ``TRAJECTORY: missing argument``, ``--bogus: no such option (did you mean --dofs?)``.
    """
    if isinstance(error, click.BadParameter):  # MissingParameter included
        name = _parameter_name(error.param, error.param_hint)
        if isinstance(error, click.MissingParameter):
            kind = "argument" if isinstance(error.param, click.Argument) else "option"
            detail = error.param.type.get_missing_message(param=error.param, ctx=error.ctx) \
                if error.param is not None else None
            what = "; ".join(part for part in (f"missing {kind}", error.message, detail) if part)
        else:
            what = error.message
    elif isinstance(error, click.NoSuchOption):
        name, what = error.option_name, "no such option" + _did_you_mean(error.possibilities)
    elif isinstance(error, click.BadOptionUsage):
        name = error.option_name
        what = re.sub(r"^Option '[^']*' ", "", error.message)
    else:
        command = re.match(r"No such command '(.*)'\.$", error.message)
        if command:
            name, what = command.group(1), _no_such_command(command.group(1), error.ctx)
        else:
            name = error.ctx.command_path if error.ctx is not None else "wipelab"
            what = error.message
    return f"{name}: {_sentence_part(what)}"


def _parameter_name(param: click.Parameter | None, hint) -> str:
    """``--particles`` for an option (its longest flag), ``TRAJECTORY`` for an argument."""
    if isinstance(hint, str):
        return hint.strip("'\"")
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    if param is not None:
        return param.human_readable_name
    return "option"


def _no_such_command(name: str, ctx: click.Context | None) -> str:
    """``no such command (did you mean learn?)``, or with the list of commands."""
    if ctx is None or not isinstance(ctx.command, click.Group):
        return "no such command"
    commands = ctx.command.list_commands(ctx)
    close = difflib.get_close_matches(name, commands)
    return "no such command" + (_did_you_mean(close) if close
                                else f" (commands: {', '.join(commands)})")


def _did_you_mean(possibilities) -> str:
    return f" (did you mean {' or '.join(possibilities)}?)" if possibilities else ""


def _sentence_part(text: str) -> str:
    """Trailing full stop off, first letter lower case (``Got unexpected`` -> ``got ...``)."""
    text = text.strip().rstrip(".")
    if len(text) > 1 and text[0].isupper() and text[1].islower():
        text = text[0].lower() + text[1:]
    return text
