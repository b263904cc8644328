"""The ``hystcomp`` program: its signal handling first, then the command line.

The console script and ``python -m hystcomp`` start here. The first lines record SIGINT,
SIGTERM and SIGHUP with CPython's own C module (``_signal``: ``signal`` itself imports
``enum``, and :mod:`hystcomp._signals` ``threading`` and ``contextlib``, 20 ms or more on
a busy machine); :func:`hystcomp._signals.install` then takes over, with any signal
already received. So a signal from the first line of hystcomp on ends the command cleanly
(:mod:`hystcomp._signals`); only Python's own start-up, before it, answers as Python does.
"""

import _signal  # type: ignore[import-not-found]  # CPython's C module behind signal

_received: list[int] = []


def _early(signum, frame) -> None:  # records, as hystcomp._signals's handler does
    _received.append(signum)


for _signum in (2, 15, 1):  # SIGINT, SIGTERM, SIGHUP (POSIX numbers; Windows has no 1)
    try:
        if _signal.getsignal(_signum) is not _signal.SIG_IGN:  # nohup, a background job
            _signal.signal(_signum, _early)
    except (OSError, ValueError):  # a signal the platform does not have
        pass

from hystcomp import _signals

_signals.install(program=True, received=_received)


def run() -> None:
    """Run the ``hystcomp`` command line (:func:`hystcomp.cli.run`)."""
    from hystcomp.cli import run as command_line

    command_line()
