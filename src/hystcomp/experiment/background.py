"""Work done in a second, forked process while ``hystcomp compare`` goes on.

:class:`BackgroundJob` computes a function there and hands its result back. The twin's
linear dynamics are identified that way from the start, with the design of their inverse
(:func:`~hystcomp.experiment.compare_dynamics.designed_twin_dynamics`: the work that needs
SciPy's optimisers, whose import alone takes 0.3 s). The paper's figures are drawn that way (:func:`draw_in_background`): :func:`hystcomp.experiment.compare.
run_comparison` hands Table I over as soon as it is measured, and the forked process draws
:data:`~hystcomp.experiment.figures.BACKGROUND_FIGURES` while the calling process goes on
with the dynamics part and then draws the others (about as much drawing each);
:func:`~hystcomp.experiment.report.write_outputs` takes the image files from it and writes
them with the tables and the report, all at once.

Where ``fork`` is not available, or if the process fails in any way, the calling process
does the job itself instead: the results are the same either way.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import sys
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: Seconds that :meth:`BackgroundJob.collect` waits at most: far beyond any job of
#: ``hystcomp compare`` (a first run's compiling takes about 7 s), so that a process that
#: hangs (a lock held at the fork) costs time, never the command.
WAIT_LIMIT = 600.0

#: The start of Python's warning on a fork in a process with threads (3.12 and later).
FORK_WARNING = r"This process \(pid=\d+\) is multi-threaded"

#: What a drawing job returns: ``{file name: None if drawn, else why not}`` (as
#: :func:`~hystcomp.experiment.figures.write_figures`).
Notes = dict[str, str | None]


class BackgroundJob:
    """``function(*args)`` run in a forked process; its result comes back (pickled).

    Start it with :meth:`start` (None where the platform cannot fork), take the result
    with :meth:`collect`.
    """

    def __init__(self, process, connection):
        self._process = process
        self._connection = connection

    @classmethod
    def start(cls, function: Callable[..., Any], *args) -> BackgroundJob | None:
        """Fork a process that computes ``function(*args)``.

        The process inherits ``args`` as they are (nothing is copied but the memory pages
        it touches). Returns None where ``fork`` is not the platform's way (only Linux
        is used: elsewhere a fork beside GUI or Objective-C libraries may hang).
        """
        if not sys.platform.startswith("linux"):
            return None
        try:
            context = multiprocessing.get_context("fork")
            receiver, sender = context.Pipe(duplex=False)
            process = context.Process(
                target=_run, args=(sender, function, args), daemon=True, name="hystcomp-job"
            )
            with warnings.catch_warnings():
                # Python >= 3.12 warns of a fork beside threads (BLAS's, here): they may hold
                # a lock the child needs. The child only computes, with NumPy, numba and
                # matplotlib, whose BLAS re-creates its threads after a fork.
                warnings.filterwarnings("ignore", FORK_WARNING, DeprecationWarning)
                process.start()
        except (OSError, ValueError):  # no fork, no pipe: the caller does the job
            return None
        sender.close()
        return cls(process, receiver)

    def collect(self, timeout: float = WAIT_LIMIT) -> Any:
        """Wait for the result: ``function(*args)``, or None if the process failed or
        gave nothing within ``timeout`` seconds (it is ended then); the caller then does
        the job itself."""
        try:
            reply = self._connection.recv() if self._connection.poll(timeout) else None
        except (EOFError, OSError):
            reply = None
        finally:
            self._connection.close()
            self._process.join(timeout=10.0 if reply else 0.0)
            if self._process.is_alive():
                self._process.kill()
                self._process.join(timeout=10.0)
        if not reply or reply[0] != "ok":
            return None
        return reply[1]

    def cancel(self) -> None:
        """End the process if it still runs, its result unread (the command failed)."""
        with contextlib.suppress(OSError, ValueError):
            self._connection.close()
            if self._process.is_alive():
                self._process.kill()
            self._process.join(timeout=10.0)


def detach_output() -> None:
    """Point a forked process's standard output and error at the null device.

    It prints nothing, and a process that held the caller's would keep a pipeline such as
    ``hystcomp compare | tail`` waiting after the caller has ended.
    """
    with contextlib.suppress(OSError, ValueError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        os.close(null)


def draw_in_background(function: Callable[..., Notes], *args) -> BackgroundJob | None:
    """A :class:`BackgroundJob` that draws ``function(*args, folder)`` into a folder of its
    own; its result is ``(notes, {file name: contents})``."""
    return BackgroundJob.start(_drawn_files, function, args)


def _drawn_files(function, args) -> tuple[Notes, dict[str, bytes]]:
    with tempfile.TemporaryDirectory(prefix="hystcomp-figures-") as folder:
        notes = function(*args, Path(folder))
        return notes, {p.name: p.read_bytes() for p in Path(folder).iterdir()}


def _run(connection, function, args) -> None:
    """The forked process: compute, send the result, or why not."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the caller's to answer
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # as the caller ends it when it exits
    detach_output()
    try:
        result = function(*args)
        connection.send(("ok", result))
    except Exception as exc:  # noqa: BLE001 - any failure: the caller does the job itself
        with contextlib.suppress(OSError):  # the caller may be gone
            connection.send(("failed", f"{type(exc).__name__}: {exc}"))
    finally:
        connection.close()
