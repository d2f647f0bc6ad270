"""The ``wipelab`` command: a thin click layer over the stage functions.

Each submodule defines the commands of one stage family; this module owns the group and
the exit-code contract: 0 success, 2 bad input or usage (one line ``error: <file or
option>: <what is wrong>``, no traceback), 1 internal failure.
"""

from __future__ import annotations

import importlib
import sys

import click

import wipelab
from wipelab.cli.usage_errors import usage_message
from wipelab.errors import InputError, from_user_interrupt
from wipelab.library_logs import silence_library_logs
from wipelab.long_lived import freeze_at_exit


#: command name -> module that defines it (imported on first use, so that ``wipelab --version``
#: or a cached pipeline step does not pay for importing OpenCV or PyBullet).
COMMAND_MODULES = {
    "synth": "wipelab.cli.vision_commands",
    "synth-dataset": "wipelab.cli.pipeline_commands",
    "track": "wipelab.cli.vision_commands",
    "learn": "wipelab.cli.learn_commands",
    "live": "wipelab.cli.live_commands",
    "rollout": "wipelab.cli.learn_commands",
    "adapt": "wipelab.cli.sim_commands",
    "replay": "wipelab.cli.sim_commands",
    "run": "wipelab.cli.pipeline_commands",
    "dataset": "wipelab.cli.pipeline_commands",
    "report": "wipelab.cli.pipeline_commands",
    "view": "wipelab.cli.pipeline_commands",
}


class _OneLineUsageError(click.UsageError):
    """A usage error shown as wipelab shows bad input: one line, exit code 2."""

    def show(self, file=None) -> None:
        click.echo(f"error: {self.message}", file=file, err=file is None)


class _WipelabGroup(click.Group):
    """Lazily loads the stage commands; turns :class:`InputError` and click's usage errors
    (of the group and of every command) into one line and exit 2."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMAND_MODULES)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        module_name = COMMAND_MODULES.get(name)
        if module_name is None:
            return None
        module = importlib.import_module(module_name)
        return getattr(module, name.replace("-", "_"))

    def make_context(self, info_name, args, parent=None, **extra) -> click.Context:
        try:
            return super().make_context(info_name, args, parent=parent, **extra)
        except click.exceptions.NoArgsIsHelpError:
            raise
        except click.UsageError as error:
            raise _OneLineUsageError(usage_message(error)) from None

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except click.UsageError as error:
            raise _OneLineUsageError(usage_message(error)) from None
        except InputError as error:
            click.echo(f"error: {error}", err=True)
            ctx.exit(2)
        except (KeyboardInterrupt, click.exceptions.Abort):
            self._interrupted(ctx)
        except SystemError as error:
            if from_user_interrupt(error):
                self._interrupted(ctx)
            raise

    @staticmethod
    def _interrupted(ctx: click.Context) -> None:
        """Ctrl-C: one line and exit code 130; a stage's files appear only when it finishes."""
        from tqdm import tqdm

        for bar in list(tqdm._instances):  # a bar the Ctrl-C cut off, even inside tqdm()
            if getattr(bar, "sp", None) is not None:  # drawn: close() alone keeps a bar it
                bar.clear(nolock=True)  # drew but had not yet timed (tqdm 4.70)
            bar.close()
        click.echo("interrupted: no output of the unfinished work was written", err=True)
        ctx.exit(130)


@click.group(cls=_WipelabGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(wipelab.__version__, prog_name="wipelab")
@click.option("-v", "--verbose", is_flag=True,
              help="Let OpenCV, FFmpeg and the other libraries print their own log lines.")
def cli(verbose: bool) -> None:
    """Teach a humanoid to wipe surfaces from a human demonstration.

    Stages: synth -> track -> learn -> adapt -> replay; run/dataset chain them.
    """
    if not verbose:
        silence_library_logs()


def main() -> None:
    """Console-script entry point."""
    try:
        sys.exit(cli.main(prog_name="wipelab"))
    finally:
        freeze_at_exit()
