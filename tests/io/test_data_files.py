"""Data files: round trips, named columns, and refusals that name file, column and fix."""

import numpy as np
import pytest
import scipy.io

from hystcomp.errors import DataFileError, InvalidParameterError, InvalidSignalError
from hystcomp.io.records import Record, parse_columns, read_record, read_table, write_table

# every test twice: text written by repr, then by the compiled formatter (read by pandas)
pytestmark = pytest.mark.usefixtures("text_reader")


@pytest.fixture
def record(rng):
    t = np.arange(500) / 5000.0
    v = 150.0 * np.sin(2 * np.pi * 10 * t)
    return {"t": t, "v": v, "x": 0.2 * v - 40.0 + 0.005 * rng.standard_normal(t.size)}


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".mat"])
def test_round_trip_is_exact(tmp_path, record, suffix):
    path = tmp_path / f"rec{suffix}"
    write_table(path, record)
    rec = read_record(path)
    for key in "tvx":
        np.testing.assert_array_equal(getattr(rec, key), record[key])
    assert rec.sample_rate == pytest.approx(5000.0)
    assert len(rec) == 500
    assert not rec.v.flags.writeable


def test_matlab_variables_as_row_or_column_vectors(tmp_path, record):
    path = tmp_path / "rec.mat"
    scipy.io.savemat(path, {"t": record["t"][None, :], "v": record["v"][:, None], "x": record["x"]})
    np.testing.assert_array_equal(read_record(path).v, record["v"])


def test_headerless_text_with_numbered_columns_and_sample_rate(tmp_path, record):
    path = tmp_path / "rig.dat"
    table = np.column_stack([record["v"], np.zeros(500), record["x"]])
    np.savetxt(path, table, delimiter="\t")
    rec = read_record(path, columns={"v": 1, "x": 3}, sample_rate=200.0)
    np.testing.assert_array_equal(rec.x, record["x"])
    np.testing.assert_allclose(rec.t, np.arange(500) / 200.0)


def test_comma_separated_txt_with_byte_order_mark(tmp_path):
    path = tmp_path / "export.txt"
    path.write_text("\ufefft,v,x\n0,0,1\n1,2,5\n", encoding="utf-8")
    assert read_record(path).v.tolist() == [0.0, 2.0]


def test_bad_column_mappings_in_python(tmp_path, record):
    path = tmp_path / "rec.csv"
    write_table(path, record)
    for bad in ({"v": 0}, {"y": 1}, {"v": True}, {"v": ""}):
        with pytest.raises(InvalidParameterError, match=r"'columns' parameter of read_record"):
            read_record(path, columns=bad)
        with pytest.raises(InvalidParameterError, match=r"'columns' parameter of read_table"):
            read_table(path, columns=bad)
    with pytest.raises(InvalidParameterError, match=r"'columns' option must look like v=1"):
        read_record(path, columns="v=1,y=2")


def test_read_record_takes_the_command_line_s_columns_text(tmp_path, record):
    path = tmp_path / "rec.csv"
    write_table(path, {"v": record["v"], "t": record["t"], "x": record["x"]})
    by_text = read_record(path, columns="t=2,v=1,x=3")
    by_dict = read_record(path, columns={"t": 2, "v": 1, "x": 3})
    for key in "tvx":
        np.testing.assert_array_equal(getattr(by_text, key), record[key])
        np.testing.assert_array_equal(getattr(by_dict, key), record[key])


def test_csv_columns_by_name_extra_columns_ignored(tmp_path):
    path = tmp_path / "rec.csv"
    path.write_text("time,volts,disp,temperature\n0,0,1,20\n0.5,1,3,20\n1,2,5,21\n")
    rec = read_record(path, columns={"t": "time", "v": "volts", "x": "disp"})
    assert rec.x.tolist() == [1.0, 3.0, 5.0]
    assert rec.sample_rate == 2.0


def test_parse_columns():
    assert parse_columns("v=1,x=5") == {"v": 1, "x": 5}
    assert parse_columns(" t=time , v=volts ") == {"t": "time", "v": "volts"}
    for bad in ("v", "y=1", "v=1,v=2", "v=", "v=0"):
        with pytest.raises(InvalidParameterError, match="columns"):
            parse_columns(bad)


def _csv(tmp_path, text, name="rec.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "kwargs", "match"),
    [
        ("t,v,x\n0,0,1\n1,nan,2\n2,1,3\n", {}, r"'v'.*non-finite value \(nan\) in data row 2"),
        ("t,v,x\n0,0,1\n1,1,2\n1,2,3\n", {}, r"not strictly increasing: data row 3 has t = 1"),
        ("t,v,x\n0,0,1\n", {}, r"has 1 sample; at least 2"),
        ("t,v,x\n0,0,1\n1,0,2\n2,0,3\n", {}, r"'v' of .* is constant \(0\.0 V\)"),
        ("t,v\n0,0\n1,1\n", {}, r"no column 'x' .*columns are t, v.*columns='x=NAME'"),
        ("v,x\n0,1\n1,2\n", {}, r"no time column 't'.*sample_rate=HZ"),
        ("t,v,x\n0,0,1\n0.1,1,2\n", {"sample_rate": 50.0}, r"says 10 Hz .* 50 Hz"),
        ("t,v,x\n0,0,1\n1,a,2\n", {}, r"numbers \(.*'a' to float64 in data row 2, column 2\)"),
        ("t,v,x\n0,0,1\n1,1\n2,1,2\n", {}, r"numbers \(data row 2 has 2 columns, not 3\)"),
        ("t,v,x\n0,0\n1,1,2\n", {}, r"not a table of numbers"),
        ("t,v,x\n", {}, r"header but no data rows"),
        ("", {}, r"is empty"),
        ("t,v,x\n0,0,1\n1,1,2\n", {"columns": {"v": 7}}, r"3 columns; column 7 for 'v'"),
        ("t,v,x\ns,V,furlong\n0,0,1\n1,1,2\n", {}, r"units row \(s, V, furlong\), but 'furlong'"),
    ],
)
def test_bad_files_are_refused_with_file_column_and_fix(tmp_path, text, kwargs, match):
    path = _csv(tmp_path, text)
    with pytest.raises(DataFileError, match=match) as err:
        read_record(path, **kwargs)
    assert "rec.csv" in str(err.value)


def test_a_title_line_above_the_header_is_no_units_row(tmp_path):
    path = _csv(tmp_path, "run 3, stage x\nt,v,x\n0,0,1\n1,1,2\n2,0,3\n")
    assert read_record(path).v.tolist() == [0.0, 1.0, 0.0]


def test_headerless_text_without_column_names_says_how(tmp_path):
    path = _csv(tmp_path, "0 1\n1 2\n", name="rig.dat")
    with pytest.raises(DataFileError, match=r"no header row.*columns='v=1,x=2'"):
        read_record(path, sample_rate=10.0)


def test_missing_file_and_named_arrays_by_number(tmp_path, record):
    with pytest.raises(DataFileError, match=r"'nowhere\.csv' does not exist"):
        read_record("nowhere.csv")
    path = tmp_path / "rec.npz"
    write_table(path, record)
    with pytest.raises(DataFileError, match=r"named arrays .* name the array for 'v'"):
        read_record(path, columns={"v": 1})


def test_npz_columns_of_different_lengths(tmp_path):
    path = tmp_path / "rec.npz"
    np.savez(path, t=np.arange(4.0), v=np.arange(4.0), x=np.arange(3.0))
    with pytest.raises(DataFileError, match=r"different lengths"):
        read_record(path)


def test_a_single_npy_array_named_npz_is_told_as_such(tmp_path):
    np.save(tmp_path / "array.npy", np.arange(3.0))
    path = (tmp_path / "array.npy").rename(tmp_path / "array.npz")
    with pytest.raises(DataFileError, match=r"single \.npy array, not named arrays"):
        read_record(path)


def test_read_table_for_inputs_and_references(tmp_path):
    path = _csv(tmp_path, "t,x\n0,1\n0.001,2\n")
    table = read_table(path, ("x",))
    assert list(table) == ["t", "x"]


def test_failed_write_never_touches_an_existing_file(tmp_path, record):
    path = tmp_path / "out.csv"
    path.write_text("precious")
    with pytest.raises(DataFileError, match=r"different lengths \(\{'t': 500, 'v': 3\}\)"):
        write_table(path, {"t": record["t"], "v": [1.0, 2.0, 3.0]})
    assert path.read_text() == "precious"
    with pytest.raises(DataFileError, match=r"unknown format '\.xlsx'"):
        write_table(tmp_path / "out.xlsx", record)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]


def test_record_sample_rate_from_time():
    rec = Record(np.array([0.0, 0.5, 1.0]), np.zeros(3), np.zeros(3))
    assert rec.sample_rate == 2.0


def test_a_time_column_beyond_the_largest_magnitude_is_refused_as_a_record_is(tmp_path):
    path = tmp_path / "rec.csv"
    path.write_text("t,v,x\n0.5,1,2\n1.5,2,3\n4.0e16,3,4\n")
    with pytest.raises(InvalidSignalError, match=r"Record 't'.*magnitude at most 1e\+12"):
        read_record(path)
