"""A progress line on standard error for steps that take more than a moment.

Rules (the same for every command): nothing is shown for a step shorter than
:data:`DELAY` seconds; after that one line is redrawn in place (``\\r``) at most every
:data:`INTERVAL` seconds and erased when the step ends. It is shown only when standard
error is a terminal: in a log file or a pipe, redrawn lines are noise, and the command's
own summary lines say what was done. ``--quiet`` turns it off. Each step reported (a
chunk read or written) is a safe point where a signal stops the command
(:func:`hystcomp._signals.check`), shown or not.
"""

from __future__ import annotations

import sys
import threading
import time

from hystcomp import _signals

#: Seconds a step runs before its progress line appears.
DELAY = 2.0
#: Fewest seconds between two redraws.
INTERVAL = 0.5


class Progress:
    """A throttled progress line: call it with the fraction done (0..1), or use it as a
    context manager around a step without fractions (it then shows the elapsed time).

    Parameters
    ----------
    label : str
        What is being done, e.g. ``"reading rec.csv"``.
    enabled : bool, optional
        Show anything at all; by default only if ``stream`` is a terminal.
    stream : file, optional
        Where to draw (standard error by default).

    Examples
    --------
    >>> import io
    >>> stream = io.StringIO()
    >>> with Progress("reading", enabled=True, stream=stream, delay=0.0) as progress:
    ...     progress(0.5)
    >>> stream.getvalue().split("\\r")[1]
    'hystcomp: reading 50 %'
    """

    def __init__(self, label: str, *, enabled=None, stream=None, delay: float = DELAY):
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        if enabled is None:
            enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self.delay = delay
        self.start = time.monotonic()
        self.last = -INTERVAL
        self.width = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __call__(self, fraction: float) -> None:
        if fraction >= 1.0:
            self.__exit__()  # done: erase the line
        else:
            _signals.check()  # a step of a chunked read or write: a safe point to stop
            self._draw(f"{100 * max(fraction, 0.0):.0f} %")

    def _draw(self, status: str, *, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if not force and (now - self.start < self.delay or now - self.last < INTERVAL):
            return
        with self._lock:
            self.last = now
            line = f"hystcomp: {self.label} {status}"
            self.stream.write("\r" + line.ljust(self.width))
            self.stream.flush()
            self.width = max(self.width, len(line))

    def _tick(self) -> None:
        while not self._stop.wait(INTERVAL):
            self._draw(f"({time.monotonic() - self.start:.0f} s)")

    def __enter__(self):
        return self

    def ticking(self):
        """Redraw the elapsed time from a background thread until the step ends."""
        if self.enabled:
            self._thread = threading.Thread(target=self._tick, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self.width:
            with self._lock:
                self.stream.write("\r" + " " * self.width + "\r")
                self.stream.flush()
                self.width = 0
