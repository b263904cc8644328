"""Fixtures of the file tests."""

import pytest

import hystcomp.io._text


@pytest.fixture(params=["repr", "compiled"])
def text_reader(request, monkeypatch):
    """Text tables written by ``repr`` (small tables), then by the compiled formatter (every
    table: the size from which it is used set to 0); read by pandas either way."""
    if request.param == "compiled":
        monkeypatch.setattr(hystcomp.io._text, "SMALL_TABLE", 0)
    return request.param
