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
    (:func:`hystcomp.cli.run`)."""
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
    from hystcomp.cli import run as command_line

    command_line()
