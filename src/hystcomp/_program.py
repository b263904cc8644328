"""The ``hystcomp`` program: its signal handling first, then the command line.

The console script and ``python -m hystcomp`` call :func:`run`, whose first lines record
SIGINT, SIGTERM and SIGHUP with CPython's own C module (``_signal``: ``signal`` itself
imports ``enum``, and :mod:`hystcomp._signals` ``threading`` and ``contextlib``, 20 ms or
more on a busy machine); :func:`hystcomp._signals.install` then takes over, with any
signal already received. So a signal from the first line of hystcomp on ends the command
cleanly (:mod:`hystcomp._signals`); only Python's own start-up, before it, answers as
Python does. Importing this module does nothing (``hystcomp/__init__`` imports nothing
either).
"""


def run() -> None:
    """Install the program's signal handling, then run the ``hystcomp`` command line
    (:func:`command_line`)."""
    import _signal  # type: ignore[import-not-found]  # CPython's C module behind signal

    received: list[int] = []

    def early(signum, frame) -> None:  # records, as hystcomp._signals's handler does
        received.append(signum)

    for signum in (2, 15, 1):  # SIGINT, SIGTERM, SIGHUP (POSIX numbers; Windows has no 1)
        try:
            if _signal.getsignal(signum) is not _signal.SIG_IGN:  # nohup, a background job
                _signal.signal(signum, early)
        except (OSError, ValueError):  # a signal the platform does not have
            pass

    from hystcomp import _signals

    _signals.install(program=True, received=received)
    command_line()


def command_line() -> None:
    """The ``hystcomp`` command line, then the process ends without tearing down.

    :func:`run` calls this, never a test (which calls :data:`hystcomp.cli.main`). Once a
    command has returned, its outputs are written, closed and renamed into place, and
    standard output and error are flushed here; what is left is the interpreter's teardown,
    which deallocates every module and compiled kernel one by one: 0.4 to 0.6 s of a 4 s
    ``hystcomp compare``, measured in alternated runs. So the process ends with
    :func:`os._exit` and the command's exit status. If a flush fails (standard output closed
    early), the normal exit path runs and reports it.
    """
    import os
    import sys

    from hystcomp import _signals
    from hystcomp.cli import main

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
