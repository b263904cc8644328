"""The ``hystcomp`` command: each subcommand in a module of its own, registered on :data:`main`.

Exit status: 0 on success, 2 on bad usage or input (one line on standard error naming the
problem and the fix), 1 on an internal fault, 141 when standard output is closed early
(``| head``), 130, 143 and 129 on SIGINT, SIGTERM and SIGHUP (temporary files removed, outputs
left as they were: :mod:`hystcomp._signals`). ``hystcomp`` alone prints its usage (exit 2).
"""

from __future__ import annotations

import contextlib
import importlib
import os
import re
import signal
import sys
import tomllib
from collections.abc import Callable
from pathlib import Path

import click

from hystcomp import _signals
from hystcomp._notice import Notice, worded
from hystcomp.errors import HystcompError, InvalidParameterError

EXIT_BAD_INPUT, EXIT_INTERNAL = 2, 1
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a command killed by it


#: The command line's words (words.toml): each command's and option's help, and the remedies
#: that the library's sentences name (:class:`hystcomp._notice.Notice`).
TEXT = tomllib.loads((Path(__file__).parent / "words.toml").read_text(encoding="utf-8"))
#: Subcommand -> (its module, its help's first line). A module is imported only when its command
#: runs or shows its help: ``hystcomp --help`` and completion load neither numba nor SciPy.
COMMANDS = {
    name: (f"hystcomp.cli.{name.replace('-', '_')}", TEXT[name]["help"].split("\n")[0])
    for name in TEXT
    if name not in ("remedies", "options")
}
#: "The 'name' parameter of owner rest": a refused parameter, said as its option's value.
_PARAMETER = re.compile(
    r"The '(?P<name>\w+)' (?:parameter|argument) of [\w.]+,? (?P<rest>[a-z0-9'].*)"
)


def command(name: str) -> Callable[[Callable], click.Command]:
    """Register a function as the subcommand ``name`` of :data:`main`, worded by words.toml.

    Parameters
    ----------
    name : str
        The subcommand, whose table in words.toml holds its help and its options' (else
        ``[options]``'s).

    Returns
    -------
    callable
        The decorator, from the function with its click options to the command.
    """
    words = {**TEXT["options"], **TEXT[name]}

    def register(function: Callable) -> click.Command:
        for param in getattr(function, "__click_params__", ()):
            flag = next((o[2:] for o in param.opts if o.startswith("--")), "")
            if isinstance(param, click.Option) and param.help is None:
                param.help = words.get(flag)
        return main.command(name, help=TEXT[name]["help"])(function)

    return register


def _say(text) -> str:
    """A library sentence, or an error's, in the command line's words (words.toml's remedies)."""
    if isinstance(text, BaseException):
        text = text.args[0] if len(text.args) == 1 else str(text)
    return " ".join(worded(text, TEXT["remedies"]).split())


class _Command(click.Command):
    """A subcommand: a library parameter refused is said as the value of its option."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InvalidParameterError as exc:
            found = _PARAMETER.fullmatch(_say(exc))
            if found is None:
                raise
            name = _say(Notice(f"{{arg_{found['name']}}}"))  # its option (words.toml)
            option = next((p for p in self.params if name in p.opts), None)
            if option is not None and ctx.params.get(option.name) is not None:  # given
                raise click.BadParameter(found["rest"], ctx, param_hint=f"'{name}'") from None
            raise


class _Group(click.Group):
    """Bad usage and hystcomp's errors as one line and exit 2; the subcommands imported from
    :data:`COMMANDS` when one runs (each registers itself), a stand-in listing it until then."""

    command_class = _Command

    def list_commands(self, ctx):
        return sorted({*COMMANDS, *self.commands})

    def get_command(self, ctx, cmd_name):  # not loaded yet: a stand-in with its help line
        if cmd_name in self.commands or cmd_name not in COMMANDS:
            return self.commands.get(cmd_name)
        return click.Command(cmd_name, help=COMMANDS[cmd_name][1])

    def resolve_command(self, ctx, args):  # the command to run (or complete): loaded now
        if args and args[0] in COMMANDS:
            importlib.import_module(COMMANDS[args[0]][0])
        return super().resolve_command(ctx, args)

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


#: What stops a command, first match: (its kind, the exit status (None: its own), the line).
_FAILURES: tuple = (
    (click.exceptions.Abort, EXIT_INTERNAL, lambda e: "aborted"),
    (click.UsageError, EXIT_BAD_INPUT, lambda e: f"error: {_say(e.format_message())}"
     + (f" (see '{e.ctx.command_path} --help')" if e.ctx is not None else "")),
    (click.ClickException, None, lambda e: f"error: {_say(e.format_message())}"),
    (HystcompError, EXIT_BAD_INPUT, lambda e: f"error: {_say(e)}"),
    (MemoryError, EXIT_BAD_INPUT, lambda e: "error: not enough memory for this input; use a "
     "shorter record, fewer operators or a lower sample rate."),
    (OSError, EXIT_BAD_INPUT, lambda e: "error: "  # the system refused a path or a write
     + importlib.import_module("hystcomp.io.atomic").refusal(e)),
    (BaseException, EXIT_INTERNAL, lambda e: f"internal error: {type(e).__name__}: "
     f"{_say(str(e))} (please report it with the command you ran)"),
)  # fmt: skip


def _failure(exc: BaseException) -> tuple[int, str | None]:
    """The exit status of a command that raised ``exc``, and the line that says why."""
    if isinstance(exc, click.exceptions.Abort) and isinstance(exc.__cause__, KeyboardInterrupt):
        exc = exc.__cause__  # Ctrl-C at a prompt of click's
    if isinstance(exc, KeyboardInterrupt):
        exc = _signals.Interrupted(signal.SIGINT)
    if isinstance(exc, _signals.Interrupted):  # its temporaries are removed by then
        return _signals.finish(exc), None
    if isinstance(exc, BrokenPipeError):  # the reader of standard output went away (| head)
        with contextlib.suppress(OSError, ValueError):  # no flush error at exit either
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE, None
    atomic = sys.modules.get("hystcomp.io.atomic")  # not imported if no file was written
    if isinstance(exc, click.exceptions.Abort | OSError) and atomic is not None:
        atomic.remove_pending()  # the temporary outputs of a failed write
    _, status, say = next(f for f in _FAILURES if isinstance(exc, f[0]))
    return status or getattr(exc, "exit_code", EXIT_INTERNAL), f"hystcomp: {say(exc)}"


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="hystcomp")
def main() -> None:
    """Identify and compensate the hysteresis of piezoelectric actuators.

    Units: voltage in V, displacement in µm, time in s.
    """
