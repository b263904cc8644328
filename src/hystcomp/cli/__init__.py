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

import click

from hystcomp import _signals
from hystcomp._notice import worded
from hystcomp.errors import HystcompError, InvalidParameterError

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 1
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a command killed by it
EXIT_SIGINT = 128 + signal.SIGINT  # 130
EXIT_SIGTERM = 128 + signal.SIGTERM  # 143
EXIT_SIGHUP = 129  # 128 + SIGHUP (POSIX)


def remove_pending() -> None:
    """Remove the temporary outputs of a failed write (none if no file module ran)."""
    atomic = sys.modules.get("hystcomp.io.atomic")  # not imported here if no file was written
    if atomic is not None:
        atomic.remove_pending()


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


#: Subcommand -> (its module, the first line of its help). A module is imported only when its
#: command runs or shows its own help, so that ``hystcomp --help``, a mistyped command and
#: shell completion load neither numba nor SciPy (tests/cli/test_cli_lazy.py checks that this
#: table matches the commands).
COMMANDS = {
    name: (f"hystcomp.cli.{name.replace('-', '_')}", text)
    for name, text in {
        "calibrate": "Print how the simulated axis (the twin) compares with the paper's figures.",
        "compare": "Identify the Preisach, PI and MPI models on the twin and compare the four "
        "methods.",
        "compensate": "Voltage that makes the actuator of MODEL.json follow REFERENCE (columns "
        "t, x).",
        "evaluate": "How well MEASURED (columns t, x; v too if there) tracked REFERENCE "
        "(columns t, x).",
        "excite": "Write the identification input for MODEL: pi, mpi, preisach, rich, "
        "dynamics, multiaxis.",
        "export-c": "Write MODEL_FILE's compensator as C99 code: NAME.h and NAME.c in folder -o.",
        "identify": "Identify a hysteresis model from DATA (columns t, v, x) and write it as JSON.",
        "raster": "An AFM raster on the simulated scanner: uncompensated, per-axis, coupled.",
        "simulate": "Run the model in MODEL.json on the voltage in INPUT (columns t, v).",
    }.items()
}

#: The remedies that the library's sentences name (:class:`hystcomp._notice.Notice`), in the
#: command's words.
WORDS = {
    "excite_rich": "hystcomp excite rich",
    "excite_mpi": "hystcomp excite mpi",
    "excite_dynamics": "hystcomp excite dynamics",
    "transient": "--transient",
    "model": "--model {others}",
    "initial_memory": "--initial-memory",
    "allow_extrapolation": "--allow-extrapolation",
    "strict": "Nothing written (--strict)",
    "drop_strict": "drop --strict",
    "method_exact": "--method exact",
    "drop_method": "Drop --method",
    "narrow": "narrow the output with --voltage-range {lo} {hi}",
    "drop_dynamics": "Drop --dynamics",
    "dynamics_option": "--dynamics",
    "identify_dynamics": "the file written by 'hystcomp identify DATA --model dynamics'",
    "pair_alone": "the hysteresis model alone (hystcomp identify without --dynamics-record)",
    "identify_pair": "hystcomp identify DATA --model KIND --dynamics-record DYN.csv",
    "slew": "--slew-rate",
    "give_fs": "give --fs",
}
#: A library parameter's option where its name is not the option's.
OPTIONS = {"sample_rate": "--fs", "out_dir": "--out"}
#: "The 'name' parameter of owner rest": a refused parameter, said as its option's value.
_PARAMETER = re.compile(
    r"The '(?P<name>\w+)' (?:parameter|argument) of [\w.]+,? (?P<rest>[a-z0-9'].*)"
)


def say(text) -> str:
    """A library sentence (a :class:`~hystcomp._notice.Notice` or text) in the command's words."""
    return _one_line(worded(text, WORDS))


def report(*results, lines: bool = True, warnings: bool = True) -> None:
    """Print the workflow results' report lines, then their warnings on standard error."""
    for result in results if lines else ():
        for line in getattr(result, "lines", ()):
            click.echo(worded(line, WORDS))
    for result in results if warnings else ():
        for warning in getattr(result, "warnings", ()):
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
            name = found and OPTIONS.get(found["name"], "--" + found["name"].replace("_", "-"))
            option = next((p for p in self.params if name in p.opts), None) if name else None
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
        except _signals.Interrupted as exc:  # (its temporaries are removed by then)
            sys.exit(_signals.finish(exc))
        except click.exceptions.Abort as exc:
            if isinstance(exc.__cause__, KeyboardInterrupt):  # click's wrapping of Ctrl-C
                sys.exit(_signals.finish(_signals.Interrupted(signal.SIGINT)))
            remove_pending()
            click.echo("hystcomp: aborted", err=True)
            sys.exit(EXIT_INTERNAL)
        except click.exceptions.NoArgsIsHelpError as exc:  # plain `hystcomp`: usage, commands
            click.echo(exc.ctx.get_help(), err=True)
            sys.exit(EXIT_BAD_INPUT)
        except click.UsageError as exc:
            hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
            click.echo(f"hystcomp: error: {_one_line(exc.format_message())}{hint}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except click.ClickException as exc:
            click.echo(f"hystcomp: error: {_one_line(exc.format_message())}", err=True)
            sys.exit(exc.exit_code)
        except HystcompError as exc:
            click.echo(
                f"hystcomp: error: {say(exc.args[0] if len(exc.args) == 1 else exc)}", err=True
            )
            sys.exit(EXIT_BAD_INPUT)
        except MemoryError:
            click.echo(
                "hystcomp: error: not enough memory for this input; use a shorter record, "
                "fewer operators or a lower sample rate.",
                err=True,
            )
            sys.exit(EXIT_BAD_INPUT)
        except BrokenPipeError:  # the reader of standard output went away (e.g. | head)
            with contextlib.suppress(OSError, ValueError):  # no flush error at exit either
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            sys.exit(EXIT_BROKEN_PIPE)
        except KeyboardInterrupt:  # raised by code, or Python's handler before ours
            sys.exit(_signals.finish(_signals.Interrupted(signal.SIGINT)))
        except OSError as exc:  # the system refused a path or a write: bad input, not a fault
            remove_pending()
            where = f" {os.fsdecode(exc.filename)[:120]!r}" if exc.filename else ""
            click.echo(
                f"hystcomp: error: cannot use{where}: {exc.strerror or exc}. Check the path "
                "(the length of its names, that its folders exist and are folders), its "
                "permissions and the free space.",
                err=True,
            )
            sys.exit(EXIT_BAD_INPUT)
        except Exception as exc:  # noqa: BLE001 - an internal fault: say so, briefly
            click.echo(
                f"hystcomp: internal error: {type(exc).__name__}: {_one_line(exc)} "
                "(please report it with the command you ran)",
                err=True,
            )
            sys.exit(EXIT_INTERNAL)


def run() -> None:
    """The ``hystcomp`` program: :data:`main`, then the process ends without tearing down.

    The console script and ``python -m hystcomp`` call this (through
    :mod:`hystcomp._program`, which installs the signal handling before anything else is
    imported), never a test (which calls :data:`main`). Once a command has returned, its
    outputs are written, closed and renamed into place, and standard output and error are
    flushed here; what is left is the interpreter's teardown, which deallocates every
    module and compiled kernel one by one: 0.4 to 0.6 s of a 4 s ``hystcomp compare``,
    measured in alternated runs. So the process ends with :func:`os._exit` and the
    command's exit status. If a flush fails (standard output closed early), the normal
    exit path runs and reports it.
    """
    code: int | str | None
    try:
        result = main(prog_name="hystcomp")  # --help and --version return 0
        code = result if isinstance(result, int) else 0
    except SystemExit as exc:
        code = exc.code
    _signals.done()  # returned: in the program, a signal from now on changes nothing
    if code is not None and not isinstance(code, int):
        sys.exit(code)  # a message: printed and exit status 1, as Python does
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):
        sys.exit(code)
    os._exit(code or 0)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="hystcomp")
def main() -> None:
    """Identify and compensate the hysteresis of piezoelectric actuators.

    Units: voltage in V, displacement in µm, time in s.
    """
