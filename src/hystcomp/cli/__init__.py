"""The ``hystcomp`` command.

Each subcommand lives in its own module of this package and registers itself on
:data:`main`. Exit status: 0 on success, 2 on bad usage or bad input (one line on
standard error that names the problem and the fix, no traceback), 1 on an internal fault,
141 when standard output is closed early (``| head``), 130 on Ctrl-C (SIGINT), 143 on
SIGTERM and 129 on SIGHUP (the terminal closed); an interrupted command removes its
temporary files and leaves its outputs as they were (:mod:`hystcomp._signals`).
``hystcomp`` alone prints its usage and commands on standard error (exit 2).
"""

from __future__ import annotations

import contextlib
import importlib
import os
import re
import signal
import sys
import tomllib
from pathlib import Path

import click

from hystcomp import _signals
from hystcomp._notice import worded
from hystcomp.errors import HystcompError, InvalidParameterError

EXIT_BAD_INPUT, EXIT_INTERNAL = 2, 1
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a command killed by it


def remove_pending() -> None:
    """Remove the temporary outputs of a failed write (none if no file module ran)."""
    atomic = sys.modules.get("hystcomp.io.atomic")  # not imported here if no file was written
    if atomic is not None:
        atomic.remove_pending()


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


#: The command line's words (words.toml): each command's and option's help, and the remedies
#: that the library's sentences name (:class:`hystcomp._notice.Notice`).
TEXT = tomllib.loads((Path(__file__).parent / "words.toml").read_text(encoding="utf-8"))
#: Subcommand -> (its module, the first line of its help). A module is imported only when its
#: command runs or shows its own help, so that ``hystcomp --help``, a mistyped command and
#: shell completion load neither numba nor SciPy (tests/cli/test_cli_lazy.py checks that this
#: table matches the commands).
COMMANDS = {
    name: (f"hystcomp.cli.{name.replace('-', '_')}", TEXT[name]["help"].split("\n")[0])
    for name in TEXT
    if name not in ("remedies", "options")
}
#: A library parameter's option where its name is not the option's.
OPTIONS = {"sample_rate": "--fs", "out_dir": "--out"}
#: "The 'name' parameter of owner rest": a refused parameter, said as its option's value.
_PARAMETER = re.compile(
    r"The '(?P<name>\w+)' (?:parameter|argument) of [\w.]+,? (?P<rest>[a-z0-9'].*)"
)


def command(name: str):
    """``main.command(name)``, with its help from words.toml."""
    return main.command(name, help=TEXT[name]["help"])


def option(command: str, *decls: str, **attrs):
    """``click.option``, with its help from words.toml: the command's own, else the shared."""
    flag = next(d for d in decls if d.startswith("--"))[2:]
    return click.option(*decls, help=TEXT[command].get(flag, TEXT["options"].get(flag)), **attrs)


def say(text) -> str:
    """A library sentence (a :class:`~hystcomp._notice.Notice` or text) in the command's words."""
    return _one_line(worded(text, TEXT["remedies"]))


def report(*results, lines: bool = True, warnings: bool = True) -> None:
    """Print the workflow results' report lines, then their warnings on standard error."""
    for line in (x for r in results if lines for x in getattr(r, "lines", ())):
        click.echo(worded(line, TEXT["remedies"]))
    for warning in (x for r in results if warnings for x in getattr(r, "warnings", ())):
        click.echo(f"hystcomp: warning: {say(warning)}", err=True)


def refuse(given: dict, why: str) -> None:
    """Refuse, in the command's words, the first option given that ``why`` does not take."""
    for option, value in given.items():
        if value is not None and value is not False:
            raise click.UsageError(f"{option} does not apply to {why}.")


class _Command(click.Command):
    """A subcommand: a library parameter refused is said as the value of its option."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InvalidParameterError as exc:
            found = _PARAMETER.fullmatch(say(exc.args[0] if len(exc.args) == 1 else exc))
            if found is None:
                raise
            name = OPTIONS.get(found["name"], "--" + found["name"].replace("_", "-"))
            option = next((p for p in self.params if name in p.opts), None)
            if option is not None and ctx.params.get(option.name) is not None:  # given
                raise click.BadParameter(found["rest"], ctx, param_hint=f"'{name}'") from None
            raise


class _Group(click.Group):
    """A click group that turns bad usage and hystcomp's errors into one line and exit 2.

    Its subcommands are imported lazily from :data:`COMMANDS`; each module registers its
    command on :data:`main` when imported.
    """

    command_class = _Command

    def list_commands(self, ctx):
        return sorted({*COMMANDS, *self.commands})

    def get_command(self, ctx, cmd_name):
        if cmd_name not in self.commands and cmd_name in COMMANDS:
            importlib.import_module(COMMANDS[cmd_name][0])
        return self.commands.get(cmd_name)

    def _short_helps(self, limit: int) -> list[tuple[str, str]]:
        """(name, short help) of every command, importing none that is not loaded yet."""
        out = []
        for name in self.list_commands(None):
            command = self.commands.get(name)
            if command is None:
                stand_in = click.Command(name, help=COMMANDS[name][1])  # shortened as click does
                out.append((name, stand_in.get_short_help_str(limit)))
            elif not command.hidden:
                out.append((name, command.get_short_help_str(limit)))
        return out

    def format_commands(self, ctx, formatter):
        rows = self._short_helps(formatter.width - 6 - max(map(len, self.list_commands(ctx))))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def shell_complete(self, ctx, incomplete):
        from click.shell_completion import CompletionItem

        items = [
            CompletionItem(name, help=text)
            for name, text in self._short_helps(45)
            if name.startswith(incomplete)
        ]
        return items + click.Command.shell_complete(self, ctx, incomplete)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            with _signals.installed():  # signals recorded; the command stops at a safe point
                return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:  # plain `hystcomp`: usage, commands
            click.echo(exc.ctx.get_help(), err=True)
            sys.exit(EXIT_BAD_INPUT)
        except (Exception, KeyboardInterrupt, _signals.Interrupted) as exc:  # noqa: BLE001
            status, message = _failure(exc)
            if message:
                click.echo(message, err=True)
            sys.exit(status)


def _failure(exc: BaseException) -> tuple[int, str | None]:
    """The exit status of a command that raised ``exc``, and the line that says why."""
    if isinstance(exc, _signals.Interrupted):  # its temporaries are removed by then
        return _signals.finish(exc), None
    abort = isinstance(exc, click.exceptions.Abort)
    if isinstance(exc, KeyboardInterrupt) or (
        abort and isinstance(exc.__cause__, KeyboardInterrupt)
    ):
        return _signals.finish(_signals.Interrupted(signal.SIGINT)), None  # Ctrl-C, or click's
    if abort:
        remove_pending()
        return EXIT_INTERNAL, "hystcomp: aborted"
    if isinstance(exc, click.UsageError):
        hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
        return EXIT_BAD_INPUT, f"hystcomp: error: {_one_line(exc.format_message())}{hint}"
    if isinstance(exc, click.ClickException):
        return exc.exit_code, f"hystcomp: error: {_one_line(exc.format_message())}"
    if isinstance(exc, HystcompError):
        return EXIT_BAD_INPUT, f"hystcomp: error: {say(exc.args[0] if len(exc.args) == 1 else exc)}"
    if isinstance(exc, MemoryError):
        return EXIT_BAD_INPUT, (
            "hystcomp: error: not enough memory for this input; use a shorter record, fewer "
            "operators or a lower sample rate."
        )
    if isinstance(exc, BrokenPipeError):  # the reader of standard output went away (| head)
        with contextlib.suppress(OSError, ValueError):  # no flush error at exit either
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE, None
    if isinstance(exc, OSError):  # the system refused a path or a write: bad input, no fault
        remove_pending()
        where = f" {os.fsdecode(exc.filename)[:120]!r}" if exc.filename else ""
        return EXIT_BAD_INPUT, (
            f"hystcomp: error: cannot use{where}: {exc.strerror or exc}. Check the path (the "
            "length of its names, that its folders exist and are folders), its permissions "
            "and the free space."
        )
    return EXIT_INTERNAL, (  # an internal fault: say so, briefly
        f"hystcomp: internal error: {type(exc).__name__}: {_one_line(exc)} (please report it "
        "with the command you ran)"
    )


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="hystcomp")
def main() -> None:
    """Identify and compensate the hysteresis of piezoelectric actuators.

    Units: voltage in V, displacement in µm, time in s.
    """
