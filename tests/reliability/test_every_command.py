"""Cases generated from the command group, for every command it has (a new one included):
its output location checked before any work, click's own usage errors as one line.

Output locations are found by convention: the ``-o/--output`` or ``--save`` option, or an
argument whose name starts with ``out``. A command must declare it with the
``OUTPUT_DIR``/``OUTPUT_FILE`` types of :mod:`wipelab.cli.options`, or these cases fail.
The not-writable cases run as a user that permission bits apply to (root ignores them):
as ``nobody`` under ``setpriv`` when the tests run as root.
"""

from __future__ import annotations

from pathlib import Path

import click
import pytest

from reliability_testdata import error_line, invoke, run_process, tree
from wipelab.cli import cli
from wipelab.cli.options import OutputLocation

CONTEXT = click.Context(cli)
COMMANDS = cli.list_commands(CONTEXT)


def output_parameter(name: str) -> click.Parameter:
    command = cli.get_command(CONTEXT, name)
    for param in command.params:
        if isinstance(param, click.Option) and {"-o", "--output", "--save"} & set(param.opts):
            return param
        if isinstance(param, click.Argument) and param.name.startswith("out"):
            return param
    raise AssertionError(f"wipelab {name}: no output option or argument found")


def output_kind(name: str) -> str:
    param = output_parameter(name)
    return param.type.kind if isinstance(param.type, OutputLocation) else "dir"


def command_line(name: str, output: str) -> list[str]:
    """``NAME`` with ``output`` as its output location first, then placeholders for every
    other required argument and option (the output is checked before they are read)."""
    command = cli.get_command(CONTEXT, name)
    out = output_parameter(name)
    argv = [name, out.opts[0], output] if isinstance(out, click.Option) else [name]
    for param in command.params:
        if param is out and isinstance(param, click.Argument):
            argv.append(output)
        elif isinstance(param, click.Argument) and param.nargs != -1:
            argv.append("INPUT")
        elif isinstance(param, click.Option) and param.required and param is not out:
            argv += [param.opts[0], "INPUT"]
    return argv


def test_every_command_declares_its_output_location():
    for name in COMMANDS:
        assert isinstance(output_parameter(name).type, OutputLocation), \
            f"wipelab {name}: declare the output with OUTPUT_DIR or OUTPUT_FILE"


@pytest.mark.parametrize("name", COMMANDS)
def test_an_output_of_the_wrong_kind_is_refused(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    if output_kind(name) == "dir":
        Path("taken").write_text("a file where a folder goes\n")
        output, says = "taken", "exists and is not a directory"
    else:
        Path("taken").mkdir()
        output, says = "taken", "is a directory, expected a file name"
    before = tree(tmp_path)
    result = invoke(command_line(name, output))
    assert result.exit_code == 2, result.output
    error_line(result.stderr, "taken", says)
    assert tree(tmp_path) == before


@pytest.mark.parametrize("name", COMMANDS)
def test_an_output_below_a_file_is_refused(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("notes.txt").write_text("a file\n")
    before = tree(tmp_path)
    result = invoke(command_line(name, "notes.txt/sub/out"))
    assert result.exit_code == 2, result.output
    error_line(result.stderr, "notes.txt/sub/out", "notes.txt is not a directory")
    assert tree(tmp_path) == before


@pytest.mark.parametrize("name", COMMANDS)
@pytest.mark.parametrize("where", ["inside", "itself"])
def test_an_output_the_user_may_not_write_is_refused(name, where, unprivileged):
    runner, folder, env = unprivileged
    kind = output_kind(name)
    if where == "inside":
        output, says = "locked/new/out", "(locked is not writable)"
    elif kind == "dir":
        output, says = "locked", "(the folder is not writable)"
    else:
        output, says = "locked/old.csv", "(locked is not writable)"
    before = tree(folder)
    completed = run_process(command_line(name, output), folder, runner.prefix, env)
    assert completed.returncode == 2, completed.stderr
    error_line(completed.stderr, output, says)
    assert tree(folder) == before


def test_the_unprivileged_user_writes_where_it_may(unprivileged):
    runner, folder, env = unprivileged
    completed = run_process(["view", "learn.rrd", "--save", "open/joined.rrd"], folder,
                            runner.prefix, env)
    assert completed.returncode == 0, completed.stderr
    assert (folder / "open" / "joined.rrd").stat().st_size > 1000


@pytest.mark.parametrize("name", COMMANDS)
def test_an_unknown_option_is_one_line(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke([name, "--bogus"])
    assert result.exit_code == 2
    error_line(result.stderr, "--bogus", "no such option")
    assert tree(tmp_path) == {}


@pytest.mark.parametrize("name", COMMANDS)
def test_a_missing_argument_is_one_line(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    first = next(p for p in cli.get_command(CONTEXT, name).params if p.required)
    result = invoke([name])
    assert result.exit_code == 2
    argument = isinstance(first, click.Argument)
    name = first.human_readable_name if argument else max(first.opts, key=len)
    error_line(result.stderr, name, f"missing {'argument' if argument else 'option'}")
    assert tree(tmp_path) == {}


@pytest.mark.parametrize("argv, names, says", [
    (["--bogus"], "--bogus", "no such option"),
    (["wipe"], "wipe", "no such command (commands: adapt, "),
    (["lear"], "lear", "no such command (did you mean learn?)"),
    (["learn", "track.csv", "-o"], "-o", "requires an argument"),
    (["learn", "track.csv", "-o", "out", "extra"], "learn", "got unexpected extra argument (extra)"),
], ids=["group-option", "command", "command-typo", "option-without-value", "extra-argument"])
def test_other_usage_errors_are_one_line(argv, names, says, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke(argv)
    assert result.exit_code == 2
    error_line(result.stderr, names, says)
