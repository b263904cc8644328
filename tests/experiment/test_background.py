"""Figures drawn in a forked process: the same files as drawn in place, or drawn in place."""

import sys

import pytest

from hystcomp.experiment.background import BackgroundFigures

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork on Linux only")


def _draw(text, folder):
    (folder / "a.png").write_bytes(text.encode() * 1000)
    (folder / "b.png").write_bytes(b"b")
    return {"b.png": None, "a.png": None, "c.png": "not drawn"}


def _fail(text, folder):
    (folder / "a.png").write_bytes(b"half")
    raise ValueError(text)


def test_the_files_and_notes_come_back_as_drawn():
    job = BackgroundFigures.start(_draw, "xyz")
    assert job is not None
    notes, files = job.collect()
    assert list(notes.items()) == [("b.png", None), ("a.png", None), ("c.png", "not drawn")]
    assert files == {"a.png": b"xyz" * 1000, "b.png": b"b"}


def test_a_failure_gives_nothing_so_that_the_caller_draws():
    job = BackgroundFigures.start(_fail, "broken")
    assert job is not None
    assert job.collect() is None
