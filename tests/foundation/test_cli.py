"""The command group: version, help on every command, the exit-code contract."""

import subprocess
import sys

import pytest
from click.testing import CliRunner

import wipelab
from wipelab.cli import COMMAND_MODULES, cli


def test_version():
    result = CliRunner().invoke(cli, ["--version"])
    assert result.exit_code == 0
    assert wipelab.__version__ in result.output


@pytest.mark.parametrize("command", sorted(COMMAND_MODULES))
def test_every_command_has_help(command):
    result = CliRunner().invoke(cli, [command, "--help"])
    assert result.exit_code == 0, result.output
    assert "Usage: " in result.output and "--help" in result.output


def test_unknown_command_is_a_usage_error():
    result = CliRunner().invoke(cli, ["wipe-everything"])
    assert result.exit_code == 2


def test_console_script_runs():
    completed = subprocess.run([sys.executable, "-m", "wipelab", "--version"],
                               capture_output=True, text=True, check=True)
    assert completed.stdout.strip() == f"wipelab, version {wipelab.__version__}"


def test_a_ctrl_c_inside_compiled_code_counts_as_an_interrupt():
    """A SIGINT handled during a numba call surfaces as a SystemError caused by it."""
    from wipelab.errors import InputError, from_user_interrupt

    def interrupted_in_compiled_code():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as interrupt:
            raise SystemError("CPUDispatcher(...) returned a result with an exception set") \
                from interrupt

    with pytest.raises(SystemError) as caught:
        interrupted_in_compiled_code()
    assert from_user_interrupt(caught.value)
    assert from_user_interrupt(KeyboardInterrupt())
    assert not from_user_interrupt(SystemError("a real internal error"))
    assert not from_user_interrupt(InputError("x.csv: bad"))


def test_a_ctrl_c_while_threads_start_comes_after_they_all_started():
    """interrupts_deferred: the block runs to its end, then the Ctrl-C is raised (a thread
    left half-started would run unjoined into Python's exit and abort the process)."""
    import signal
    import threading

    from wipelab.errors import interrupts_deferred

    release = threading.Event()
    threads = [threading.Thread(target=release.wait) for _ in range(2)]
    with pytest.raises(KeyboardInterrupt):
        with interrupts_deferred():
            signal.raise_signal(signal.SIGINT)
            for thread in threads:
                thread.start()
    assert all(thread.is_alive() for thread in threads)
    release.set()
    for thread in threads:
        thread.join()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
