"""N-axis data files: columns found by name in any case, or mapped; refusals name the fix."""

from __future__ import annotations

import numpy as np
import pytest

from hystcomp.errors import DataFileError, InvalidParameterError
from hystcomp.io.multiaxis import is_multiaxis, parse_axis_columns, read_axes
from hystcomp.io.records import write_table


@pytest.fixture
def record(tmp_path):
    n = 50
    t = np.arange(n) / 1000.0
    table = {"t": t, "V1": t * 10, "v2": t * 20, "X1": t * 3, "x2": t * 4}
    path = tmp_path / "rec.csv"
    write_table(path, table)
    return path, table


def test_columns_are_found_by_name_in_any_case(record):
    path, table = record
    assert is_multiaxis(path)
    got = read_axes(path)
    assert got["v"].shape == (50, 2)
    assert np.array_equal(got["v"][:, 1], table["v2"])
    assert np.array_equal(got["x"][:, 0], table["X1"])
    assert np.array_equal(got["t"], table["t"])


def test_columns_can_be_mapped(tmp_path):
    path = tmp_path / "lab.csv"
    n = 20
    write_table(path, {"time": np.arange(n) / 100.0, "ux": np.arange(n) * 1.0, "uy": np.ones(n)})
    assert not is_multiaxis(path)
    columns = parse_axis_columns("t=time,x1=ux,x2=uy")
    assert is_multiaxis(path, columns)
    got = read_axes(path, ("x",), columns=columns)
    assert np.array_equal(got["x"][:, 0], np.arange(n) * 1.0)


def test_a_missing_axis_column_names_it(tmp_path):
    path = tmp_path / "gap.csv"
    n = 10
    write_table(
        path, {"t": np.arange(n) / 10, "v1": np.ones(n), "v2": np.ones(n), "x1": np.ones(n)}
    )
    with pytest.raises(DataFileError, match="no column 'x2'"):
        read_axes(path)


def test_displacements_in_other_units_are_converted(record):
    path, table = record
    got = read_axes(path, ("x",), x_unit="nm")
    assert np.allclose(got["x"][:, 1], table["x2"] * 1e-3)


@pytest.mark.parametrize("text", ["v1", "v1=2,v1=3", "y1=2", "v0=1"])
def test_bad_column_maps_are_refused(text):
    with pytest.raises(InvalidParameterError, match="t=1,v1=2"):
        parse_axis_columns(text)
