"""Fixtures of the file tests."""

import pytest

import hystcomp.io._text


@pytest.fixture(params=["numpy", "compiled"])
def text_reader(request, monkeypatch):
    """Text tables read by ``numpy.loadtxt`` (small tables), then by the compiled parser and
    formatter (every table: the size from which they are used set to 0)."""
    if request.param == "compiled":
        monkeypatch.setattr(hystcomp.io._text, "SMALL_TABLE", 0)
        monkeypatch.setattr(hystcomp.io._text, "SMALL_READ", 0)
    return request.param
