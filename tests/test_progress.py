"""The progress line: only on a terminal, only after the delay, erased at the end."""

import io
import time

from hystcomp._progress import INTERVAL, Progress


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_silent_off_a_terminal_and_before_the_delay():
    log = io.StringIO()
    with Progress("reading", stream=log, delay=0.0) as progress:
        progress(0.5)
    assert log.getvalue() == ""
    terminal = _Terminal()
    with Progress("reading", stream=terminal) as progress:  # the 2 s delay has not passed
        progress(0.5)
    assert terminal.getvalue() == ""


def test_drawn_in_place_throttled_and_erased():
    terminal = _Terminal()
    progress = Progress("writing out.csv", stream=terminal, delay=0.0)
    for i in range(100):
        progress(i / 100)  # all within one interval: drawn once
    progress(1.0)
    text = terminal.getvalue()
    assert text.count("hystcomp: writing out.csv") == 1
    assert text.startswith("\rhystcomp: writing out.csv 0 %")
    assert text.endswith("\r" + " " * len("hystcomp: writing out.csv 0 %") + "\r")


def test_ticking_shows_elapsed_seconds():
    terminal = _Terminal()
    with Progress("identifying", stream=terminal, delay=0.0).ticking():
        time.sleep(2.5 * INTERVAL)
    assert "hystcomp: identifying (" in terminal.getvalue()
    assert terminal.getvalue().endswith("\r")
