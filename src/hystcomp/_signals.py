"""Ctrl-C, SIGTERM and SIGHUP end a command cleanly, whatever it is doing at that moment.

An exception raised from a Python signal handler lands wherever the main thread happens to
run Python code: inside a callback from llvmlite or another C extension (which swallows
it, and the command went on to replace its outputs, exit status 0), inside an import
(``ImportError: initialization failed``), or between two steps of a library's state.
So the handlers here raise nothing. They record the signal, and the command stops at a
*safe point*:

* :func:`check`, called where stopping is harmless: at each step of a progress line (a
  file written or read in chunks), while waiting for a forked process, between the steps
  of ``hystcomp compare``; it raises :class:`Interrupted`, a ``BaseException`` that no
  ``except Exception`` swallows, and the stack unwinds through the ``finally`` blocks
  that remove temporary files;
* :func:`commit`, around the renames that put a command's outputs into place
  (:func:`hystcomp.io.atomic.replace_all`): it refuses once a signal is pending, so an
  interrupted command replaces no output. Once a command's outputs are committed the
  command completes (exit status 0): the signal came too late to stop it.

The program (``hystcomp``, :func:`install` with ``program=True``) also has a watcher: the
signal wakes it at once through :func:`signal.set_wakeup_fd`, even while the main thread
runs a compiled kernel or an optimiser for seconds, where no safe point comes. If the
command has not stopped :data:`GRACE` seconds later (or a second signal comes), the
watcher ends the process itself: under the lock that every commit and every new
temporary file takes (so none is under way, and none starts after it), it removes the
temporaries, ends the forked helper processes, writes the one line and calls
:func:`os._exit`. Either way the exit status is 128 + the signal's number (130 for
SIGINT, 143 for SIGTERM, 129 for SIGHUP), standard error has one line, no output is
replaced and no temporary is left. :func:`os._exit` also skips the interpreter's
teardown, which would deallocate numba's and llvmlite's state half way through a
computation (an interrupted run once ended in a double free).

Called as a library (``main([...])`` in a test or a notebook), the handlers are installed
for the command's duration only, without the watcher: a signal stops the command at its
next safe point, and :class:`Interrupted` becomes ``SystemExit(128 + n)``.

A leaf: the standard library only. The program (:func:`hystcomp._program.run`) records
signals from its first line and hands them over here, so that only Python's own
start-up, before any line of hystcomp runs, keeps Python's behaviour.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable

#: The signals handled, and the word of the one line each leaves on standard error.
WORDS: dict[int, str] = {
    int(signal.SIGINT): "interrupted",
    int(signal.SIGTERM): "terminated",
}
if hasattr(signal, "SIGHUP"):  # POSIX
    WORDS[int(signal.SIGHUP)] = "hung up (the terminal closed)"

#: Seconds the program waits, after a signal, for the command to stop at a safe point
#: before the watcher ends it.
GRACE = 0.5


class Interrupted(BaseException):
    """A signal stops the command (raised at a safe point, never in a signal handler).

    A ``BaseException``, as ``KeyboardInterrupt``: ``except Exception`` does not catch it.

    Attributes
    ----------
    signum : int
        The signal's number.
    """

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    @property
    def exit_status(self) -> int:
        """128 + the signal's number, as a shell reports a command ended by it."""
        return 128 + self.signum


class _State:
    """What the handlers, the safe points and the watcher share (under :data:`LOCK`)."""

    def __init__(self) -> None:
        self.signum: int | None = None  # the first signal received
        self.committed = False  # a command's outputs are in place: it completes
        self.program = False  # the watcher may end the process
        self.installed = 0  # nesting of install()
        self.cleanups: list[Callable[[], None]] = []
        self.children: set[int] = set()  # forked helper processes, ended on the way out


#: Held by every commit, every registration of a temporary file and the watcher's exit.
LOCK = threading.RLock()
_state = _State()


def _after_fork_in_child() -> None:
    """A forked process starts unlocked, without signals pending, and with nothing of its
    parent's to clean up (the parent's temporaries are the parent's)."""
    global LOCK
    LOCK = threading.RLock()
    _state.signum = None
    _state.program = False
    _state.cleanups = []
    _state.children = set()


def lock() -> threading.RLock:
    """:data:`LOCK` (looked up at each call: a forked process has a new one)."""
    return LOCK


if hasattr(os, "register_at_fork"):  # POSIX
    os.register_at_fork(after_in_child=_after_fork_in_child)


def add_cleanup(function: Callable[[], None]) -> None:
    """Call ``function()`` (under :data:`LOCK`) when a signal ends the command: it must be
    quick, import nothing and raise nothing (e.g. remove the pending temporary files)."""
    with LOCK:
        if function not in _state.cleanups:
            _state.cleanups.append(function)


def adopt_child(pid: int) -> None:
    """End the forked process ``pid`` (SIGKILL) if a signal ends the command."""
    with LOCK:
        _state.children.add(pid)


def release_child(pid: int) -> None:
    """Forget ``pid`` (it was collected or ended)."""
    with LOCK:
        _state.children.discard(pid)


def pending() -> int | None:
    """The number of the signal received, or None."""
    return _state.signum


def _record(signum: int) -> None:
    if _state.signum is None:  # the first one counts (no lock: a handler must not block)
        _state.signum = signum


def _handler(signum, frame) -> None:
    _record(signum)  # nothing else: see the module's docstring


def check() -> None:
    """A safe point: raise :class:`Interrupted` if a signal is pending (in the main
    thread, before the command's outputs are committed)."""
    signum = _state.signum
    if (
        signum is not None
        and not _state.committed
        and threading.current_thread() is threading.main_thread()
    ):
        raise Interrupted(signum)


@contextlib.contextmanager
def commit(*, final: bool = True):
    """Hold :data:`LOCK` around the renames that put outputs into place, refusing
    (:class:`Interrupted`) once a signal is pending.

    ``final`` (a command's own outputs, not a temporary file renamed onto another one
    inside a nested writer) marks the command as committed when the renames succeed: it
    then completes whatever signal comes.
    """
    with LOCK:
        signum = _state.signum
        if signum is not None and not _state.committed:
            raise Interrupted(signum)
        yield
        if final:
            _state.committed = True


def done() -> None:
    """The program's command has returned: it completes whatever signal comes now (called
    as a library, nothing: :func:`installed` ends with the command)."""
    if _state.program:
        with LOCK:
            _state.committed = True


def line(signum: int) -> str:
    """The one line a signal leaves on standard error."""
    return f"hystcomp: {WORDS.get(signum, f'signal {signum}')}"


def _cleanup() -> None:
    """Under :data:`LOCK`: the registered cleanups, then the forked helpers ended."""
    for function in list(_state.cleanups):
        with contextlib.suppress(BaseException):
            function()
    for pid in list(_state.children):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    _state.children.clear()


def abort(signum: int) -> None:
    """End the program for ``signum``: cleanups, one line, exit 128 + ``signum``.

    Returns (doing nothing) only if the command's outputs are committed: it completes.
    """
    with LOCK:  # no commit under way; none, and no temporary file, starts after this
        if _state.committed:
            return
        _cleanup()
        with contextlib.suppress(OSError):
            os.write(2, (line(signum) + "\n").encode())
        os._exit(128 + signum)


def finish(exc: Interrupted) -> int:
    """How the command line ends a command stopped by ``exc``: in the program, through
    :func:`abort`; called as a library, the cleanups and the line, and the exit status
    to return."""
    if _state.program:
        import sys  # loaded: the interpreter's own

        with contextlib.suppress(OSError, ValueError):  # what the command printed so far
            sys.stdout.flush()
        abort(exc.signum)
        return 0  # committed meanwhile: the command completed
    with LOCK:
        _cleanup()
    with contextlib.suppress(OSError, ValueError):
        import sys

        sys.stderr.write(line(exc.signum) + "\n")
        sys.stderr.flush()
    return exc.exit_status


def _watch(read_fd: int) -> None:
    """The program's watcher: woken by the first signal's byte, it waits :data:`GRACE`
    seconds (or for a second signal) and then ends the process (:func:`abort`)."""
    signum = None
    while True:
        try:
            data = os.read(read_fd, 64)
        except InterruptedError:
            continue
        except OSError:
            return
        got = [b for b in data if b in WORDS]
        if not got:
            continue
        if signum is None:
            signum = got[0]
            _record(signum)
            if len(got) == 1:
                deadline = time.monotonic() + GRACE
                os.set_blocking(read_fd, False)
                while time.monotonic() < deadline:  # a second signal ends the wait
                    time.sleep(0.01)
                    with contextlib.suppress(BlockingIOError, InterruptedError):
                        if any(b in WORDS for b in os.read(read_fd, 64)):
                            break
                os.set_blocking(read_fd, True)
        abort(_state.signum or signum)
        # committed: the command completes by itself; later signals change nothing


def install(*, program: bool = False, received=()) -> None:
    """Record SIGINT, SIGTERM and SIGHUP from now on (see the module); with ``program``,
    start the watcher too, and take over the signals ``received`` by an earlier handler
    (:mod:`hystcomp._program`'s). Idempotent; only from the main thread (elsewhere,
    nothing)."""
    if threading.current_thread() is not threading.main_thread():
        return
    for signum in WORDS:
        if signal.getsignal(signum) is not signal.SIG_IGN:  # nohup, a background job
            signal.signal(signum, _handler)
    if program and not _state.program and os.name == "posix":  # (a pipe as wake-up fd)
        read_fd, write_fd = os.pipe()
        os.set_blocking(write_fd, False)
        signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
        threading.Thread(
            target=_watch, args=(read_fd,), name="hystcomp-signals", daemon=True
        ).start()
        _state.program = True
        for signum in list(received)[:2]:  # as if they came now: the watcher's clock starts
            _record(signum)
            with contextlib.suppress(OSError):
                os.write(write_fd, bytes([signum]))
    elif received:
        _record(received[0])


@contextlib.contextmanager
def installed():
    """:func:`install` for the duration of a command run as a library (the handlers as
    they were afterwards); in the program, nothing more than what is installed."""
    if _state.program or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in WORDS}
    if not _state.installed:  # a command starts with nothing pending nor committed
        _state.signum = None
        _state.committed = False
    _state.installed += 1
    install()
    try:
        yield
    finally:
        _state.installed -= 1
        if not _state.installed:
            for signum, handler in previous.items():
                signal.signal(signum, handler)
            _state.signum = None
            _state.committed = False
