"""Figures drawn in a second process while the experiment goes on (``hystcomp compare``).

The paper's figures need only Table I's runs: :func:`hystcomp.experiment.compare.run_comparison`
hands Table I over as soon as it is measured, and a forked process draws
:data:`~hystcomp.experiment.figures.BACKGROUND_FIGURES` while the calling process goes on
with the dynamics part and then draws the others (about as much drawing each);
:func:`~hystcomp.experiment.report.write_outputs` takes the image files from it and writes
them with the tables and the report, all at once. Where ``fork`` is not available, or if
the process fails in any way, those figures are drawn in the calling process instead: the
files are the same either way.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
import sys
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

#: The start of Python's warning on a fork in a process with threads (3.12 and later).
FORK_WARNING = r"This process \(pid=\d+\) is multi-threaded"

#: What a drawing job returns: ``{file name: None if drawn, else why not}`` (as
#: :func:`~hystcomp.experiment.figures.write_figures`).
Notes = dict[str, str | None]


class BackgroundFigures:
    """``function(*args, folder) -> notes`` run in a forked process; its files come back.

    Start it with :meth:`start` (None where the platform cannot fork), take the result
    with :meth:`collect`.
    """

    def __init__(self, process, connection):
        self._process = process
        self._connection = connection

    @classmethod
    def start(cls, function: Callable[..., Notes], *args) -> BackgroundFigures | None:
        """Fork a process that draws ``function(*args, folder)`` into a folder of its own.

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
                target=_draw, args=(sender, function, args), daemon=True, name="hystcomp-figures"
            )
            with warnings.catch_warnings():
                # Python >= 3.12 warns of a fork beside threads (BLAS's, here): they may hold
                # a lock the child needs. The child only draws, with matplotlib and NumPy,
                # whose BLAS re-creates its threads after a fork.
                warnings.filterwarnings("ignore", FORK_WARNING, DeprecationWarning)
                process.start()
        except (OSError, ValueError):  # no fork, no pipe: draw in this process
            return None
        sender.close()
        return cls(process, receiver)

    def collect(self) -> tuple[Notes, dict[str, bytes]] | None:
        """Wait for the drawings: ``(notes, {file name: contents})``, or None if the
        process failed (the caller then draws the figures itself)."""
        try:
            reply = self._connection.recv()
        except (EOFError, OSError):
            reply = None
        finally:
            self._connection.close()
            self._process.join(timeout=10.0)
            if self._process.is_alive():
                self._process.kill()
        if not reply or reply[0] != "ok":
            return None
        return reply[1], reply[2]


def _draw(connection, function, args) -> None:
    """The forked process: draw, send the notes and the files' bytes, or why not."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the caller's to answer
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # as the caller ends it when it exits
    try:
        with tempfile.TemporaryDirectory(prefix="hystcomp-figures-") as folder:
            notes = function(*args, Path(folder))
            files = {p.name: p.read_bytes() for p in Path(folder).iterdir()}
        connection.send(("ok", notes, files))
    except Exception as exc:  # noqa: BLE001 - any failure: the caller draws them itself
        with contextlib.suppress(OSError):  # the caller may be gone
            connection.send(("failed", f"{type(exc).__name__}: {exc}", {}))
    finally:
        connection.close()
