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

Signals (:mod:`hystcomp._signals`): the forked process leaves Ctrl-C to the caller and
ends on SIGTERM and SIGHUP; the caller waits for it in short polls, each a safe point,
and a signal that ends the caller ends the process too. A drawing job draws into a
folder that the caller made and removes (a temporary of the caller's), never one that a
killed process would leave behind.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from hystcomp import _signals

#: Seconds that :meth:`BackgroundJob.collect` waits at most: far beyond any job of
#: ``hystcomp compare`` (a first run's compiling takes about 7 s), so that a process that
#: hangs (a lock held at the fork) costs time, never the command.
WAIT_LIMIT = 600.0

#: Seconds between two looks at a job's result, each a safe point for a signal.
POLL = 0.05

#: The start of Python's warning on a fork in a process with threads (3.12 and later).
FORK_WARNING = r"This process \(pid=\d+\) is multi-threaded"

#: What a drawing job returns: ``{file name: None if drawn, else why not}`` (as
#: :func:`~hystcomp.experiment.figures.write_figures`).
Notes = dict[str, str | None]


class BackgroundJob:
    """``function(*args)`` run in a forked process; its result comes back (pickled).

    Start it with :meth:`start` (None where the platform cannot fork), take the result
    with :meth:`collect`.

    Parameters
    ----------
    process : multiprocessing.Process
        The forked process, started.
    connection : multiprocessing.connection.Connection
        The end of the pipe the result comes back on.
    folder : pathlib.Path, optional
        A temporary folder of the caller's, removed once the job is collected or cancelled.
    """

    def __init__(self, process, connection, folder: Path | None = None):
        self._process = process
        self._connection = connection
        self._folder = folder  # the caller's temporary folder for the job, removed after it

    @classmethod
    def start(
        cls, function: Callable[..., Any], *args, folder: Path | None = None
    ) -> BackgroundJob | None:
        """Fork a process that computes ``function(*args)``.

        The process inherits ``args`` as they are (nothing is copied but the memory pages
        it touches). Returns None where ``fork`` is not the platform's way (only Linux
        is used: elsewhere a fork beside GUI or Objective-C libraries may hang).
        ``folder``, a temporary folder of the caller's for the job, is removed once the
        job is collected or cancelled.

        Parameters
        ----------
        function : callable
            What to compute; its result must pickle.
        *args
            Its arguments, inherited by the process as they are.
        folder : pathlib.Path, optional
            A temporary folder for the job, removed once it is collected or cancelled.

        Returns
        -------
        BackgroundJob or None
            The running job, or None where the platform does not fork.
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
                # forked and adopted under the signals' lock, and not once a signal is
                # pending: a process forked after the signal and before its adoption
                # would outlive the caller (it never saw the signal)
                with _signals.lock():
                    _signals.check()
                    process.start()
                    if process.pid is not None:
                        _signals.adopt_child(process.pid)  # ended with the caller on a signal
        except (OSError, ValueError):  # no fork, no pipe: the caller does the job
            return None
        sender.close()
        return cls(process, receiver, folder)

    def collect(self, timeout: float = WAIT_LIMIT) -> Any:
        """Wait for the result: ``function(*args)``, or None if the process failed or
        gave nothing within ``timeout`` seconds (it is ended then); the caller then does
        the job itself. It waits in polls of :data:`POLL` seconds, each a safe point for a
        signal (:func:`hystcomp._signals.check`).

        Parameters
        ----------
        timeout : float, optional
            The longest wait, s.

        Returns
        -------
        object
            ``function(*args)``, or None if the process failed or timed out.
        """
        reply = None
        try:
            deadline = time.monotonic() + timeout
            while True:
                _signals.check()
                if self._connection.poll(min(POLL, max(0.0, deadline - time.monotonic()))):
                    reply = self._connection.recv()
                    break
                if time.monotonic() >= deadline:
                    break
        except (EOFError, OSError):
            reply = None
        finally:
            self._connection.close()
            self._process.join(timeout=10.0 if reply else 0.0)
            if self._process.is_alive():
                self._process.kill()
                self._process.join(timeout=10.0)
            self._release()
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
        self._release()

    def _release(self) -> None:
        """The process is gone: forget it, and remove the job's folder."""
        if self._process.pid is not None:
            _signals.release_child(self._process.pid)
        if self._folder is not None:
            from hystcomp.io.atomic import discard_temporary

            discard_temporary(self._folder)
            self._folder = None


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
    own (made and removed by the caller); its result is ``(notes, {file name: contents})``.

    Parameters
    ----------
    function : callable
        ``function(*args, folder) -> notes``, which draws figures into ``folder``.
    *args
        Its arguments.

    Returns
    -------
    BackgroundJob or None
        The running job, or None where the platform does not fork.
    """
    from hystcomp.io.atomic import new_temporary_folder

    folder = new_temporary_folder("hystcomp-figures-")
    job = BackgroundJob.start(_drawn_files, function, args, folder, folder=folder)
    if job is None:
        from hystcomp.io.atomic import discard_temporary

        discard_temporary(folder)
    return job


def _drawn_files(function, args, folder: Path) -> tuple[Notes, dict[str, bytes]]:
    notes = function(*args, folder)
    return notes, {p.name: p.read_bytes() for p in folder.iterdir()}


def _run(connection, function, args) -> None:
    """The forked process: compute, send the result, or why not."""
    with contextlib.suppress(ValueError):  # the caller's wake-up pipe is the caller's
        signal.set_wakeup_fd(-1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the caller's to answer
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # as the caller ends it when it exits
    signal.signal(signal.SIGHUP, signal.SIG_DFL)  # (fork: POSIX only)
    detach_output()
    try:
        result = function(*args)
        connection.send(("ok", result))
    except Exception as exc:  # noqa: BLE001 - any failure: the caller does the job itself
        with contextlib.suppress(OSError):  # the caller may be gone
            connection.send(("failed", f"{type(exc).__name__}: {exc}"))
    finally:
        connection.close()
