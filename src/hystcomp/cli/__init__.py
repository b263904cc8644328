"""The ``hystcomp`` command.

Each subcommand lives in its own module of this package and registers itself on
:data:`main`. Exit status: 0 on success, 2 on bad usage or bad input (one line, no
traceback), 1 on an internal fault.
"""

from __future__ import annotations

import sys

import click

from hystcomp.errors import HystcompError

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 1


class _Group(click.Group):
    """A click group that turns hystcomp's errors into one line and exit status 2."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.Abort:
            click.echo("hystcomp: aborted", err=True)
            sys.exit(EXIT_INTERNAL)
        except click.ClickException as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except HystcompError as exc:
            click.echo(f"hystcomp: error: {exc}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except KeyboardInterrupt:
            click.echo("hystcomp: interrupted", err=True)
            sys.exit(130)
        except Exception as exc:  # noqa: BLE001 - an internal fault: say so, briefly
            click.echo(
                f"hystcomp: internal error: {type(exc).__name__}: {exc} "
                "(please report it with the command you ran)",
                err=True,
            )
            sys.exit(EXIT_INTERNAL)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="hystcomp")
def main() -> None:
    """Identify and compensate the hysteresis of piezoelectric actuators.

    Units: voltage in V, displacement in µm, time in s.
    """


# The subcommands register themselves on main when imported.
from hystcomp.cli import compare  # noqa: F401
