"""The files labs have: each layout reads as the canonical t,v,x CSV; limits; units."""

import os
import subprocess
import sys
import zipfile

import numpy as np
import pytest
import scipy.io
from click.testing import CliRunner

from hystcomp.cli import main
from hystcomp.errors import DataFileError, InvalidParameterError
from hystcomp.io._formats import MAX_SAMPLES, max_samples
from hystcomp.io.records import read_record, read_table, write_table, x_unit_warning

# every test twice: text written by repr, then by the compiled formatter (read by pandas)
pytestmark = pytest.mark.usefixtures("text_reader")


@pytest.fixture
def record(rng):
    t = np.arange(300) / 2000.0
    v = 60.0 + 50.0 * np.sin(2 * np.pi * 5 * t)
    return {"t": t, "v": v, "x": 0.2 * v - 40.0 + 0.005 * rng.standard_normal(t.size)}


def _rows(record, sep=",", decimal="."):
    return [
        sep.join(repr(float(record[k][i])).replace(".", decimal) for k in "tvx")
        for i in range(record["t"].size)
    ]


def _same(path, record, **kwargs):
    rec = read_record(path, **kwargs)
    for key in "tvx":
        np.testing.assert_array_equal(getattr(rec, key), record[key])


@pytest.mark.parametrize(
    ("name", "head", "sep", "decimal"),
    [
        ("semicolon.csv", ["t;v;x"], ";", "."),
        ("comma-decimal.csv", ["t;v;x"], ";", ","),
        ("comma-decimal-tabs.txt", ["t\tv\tx"], "\t", ","),
        ("numpy-header.txt", ["# t,v,x"], ",", "."),
        ("comments.csv", ["# rig 3, 2026-11-02", "# operator: A.B.", "t,v,x"], ",", "."),
        ("units.csv", ["t,v,x", "s,V,um"], ",", "."),
        ("units-brackets.csv", ["t;v;x", "[s];[V];[µm]"], ";", ","),
        ("comment-units.dat", ["# t v x", "# (s) (V) (um)"], " ", "."),
        ("comment-header-then-note.csv", ["# t,v,x", "# operator: A.B."], ",", "."),
        ("comment-header-units-note.csv", ["# rig 3", "# t,v,x", "# s,V,um", "# note"], ",", "."),
        ("upper.csv", ["T,V,X"], ",", "."),
        ("names-units.csv", ["t [s];V (V);x [µm]"], ";", ","),
        ("mixed.csv", ['"Time","v","X"'], ",", "."),
        ("crlf.csv", ["t,v,x"], ",", "."),
        ("spaces-decimal-comma.txt", ["t v x"], " ", ","),
        ("spaces-decimal-comma-runs.dat", ["t    v    x"], "    ", ","),
        ("cr.csv", ["t,v,x"], ",", "."),
    ],
)
def test_lab_text_layouts_read_as_the_canonical_csv(tmp_path, record, name, head, sep, decimal):
    path = tmp_path / name
    newline = {"crlf.csv": "\r\n", "cr.csv": "\r"}.get(name, "\n")
    path.write_text(newline.join([*head, *_rows(record, sep, decimal)]) + newline, "utf-8")
    columns = {"t": "time"} if name.startswith("mixed") else None
    _same(path, record, columns=columns)


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_long_tables_with_blank_lines_and_old_mac_line_ends_are_read(tmp_path, rng, newline):
    import hystcomp.io._text as text

    t = np.arange(6000) / 2000.0  # longer than the head that the layout is read from
    big = {"t": t, "v": 60.0 + 50.0 * np.sin(t), "x": rng.standard_normal(t.size)}
    rows = _rows(big)
    for k in (3, 2500, 5999):  # lines of spaces and tabs, as editors leave them
        rows[k] += newline + " \t "
    path = tmp_path / "long.csv"
    path.write_bytes(newline.join(["t,v,x", *rows, ""]).encode())
    assert path.stat().st_size > text.HEAD_BYTES
    _same(path, big)


@pytest.mark.parametrize(
    ("name", "head", "sep", "decimal", "edit"),
    [
        ("quoted.csv", ['"t","v","x"'], ",", ".", lambda row, sep: sep.join(f'"{f}"' for f in row.split(sep))),
        ("quoted-decimal-comma.csv", ["t;v;x"], ";", ",", lambda row, sep: sep.join(f'"{f}"' for f in row.split(sep))),
        ("trailing.csv", ["t,v,x,"], ",", ".", lambda row, sep: row + sep),
        ("trailing-data-only.csv", ["t,v,x"], ",", ".", lambda row, sep: row + sep),
        ("trailing-units.csv", ["t;v;x;", "s;V;mm;"], ";", ",", lambda row, sep: row + sep),
        ("trailing-tabs.txt", ["t\tv\tx\t"], "\t", ".", lambda row, sep: row + sep),
    ],
)  # fmt: skip
def test_spreadsheet_quotes_and_trailing_separators_are_read(
    tmp_path, record, name, head, sep, decimal, edit
):
    path = tmp_path / name
    rows = [edit(row, sep) for row in _rows(record, sep, decimal)]
    path.write_text("\n".join([*head, *rows]) + "\n", "utf-8")
    expected = dict(record, x=record["x"] * 1e3) if "units" in name else record  # mm
    rec = read_record(path)
    for key in "tv":
        np.testing.assert_array_equal(getattr(rec, key), expected[key])
    np.testing.assert_allclose(rec.x, expected["x"], rtol=1e-15)
    # a row that misses a value is still refused, with where
    path.write_text("\n".join([*head, *rows[:3], sep.join(["1"] * 2), *rows[3:]]) + "\n")
    with pytest.raises(DataFileError, match="not a table of numbers"):
        read_record(path)


def test_a_windows_1252_table_is_read_and_binary_data_still_refused(tmp_path, record):
    path = tmp_path / "windows.csv"
    rows = _rows(record, ";", ",")
    text = "\r\n".join(["Zeit;Spannung;Weg", "s;V;µm", *rows[:5], "# 23 °C", *rows[5:]])
    path.write_bytes(text.encode("cp1252"))
    _same(path, record, columns={"t": "zeit", "v": "spannung", "x": "weg"})
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"t,v,x\n" + bytes(range(256)) * 4)
    with pytest.raises(DataFileError, match="is not text"):
        read_record(binary)


def test_numpy_savetxt_header_and_semicolon_comma_export(tmp_path, record):
    table = np.column_stack([record[k] for k in "tvx"])
    path = tmp_path / "savetxt.txt"
    np.savetxt(path, table, delimiter=",", header="t,v,x", fmt="%.17g")
    _same(path, record)
    canonical = tmp_path / "rec.csv"
    write_table(canonical, record)
    german = tmp_path / "export.csv"
    german.write_text(canonical.read_text().replace(",", ";").replace(".", ","), "utf-8")
    _same(german, record)


def test_units_row_in_mm_is_converted(tmp_path, record):
    path = tmp_path / "mm.csv"
    mm = {**record, "x": record["x"] / 1000.0}
    path.write_text("\n".join(["t,v,x", "s,V,mm", *_rows(mm)]) + "\n")
    rec = read_record(path)
    np.testing.assert_allclose(rec.x, record["x"], rtol=1e-15)
    with pytest.raises(DataFileError, match=r"units row .* says the displacement is in mm"):
        read_record(path, x_unit="um")
    path.write_text("\n".join(["Time (s),v [V],x [mm]", *_rows(mm)]) + "\n")
    np.testing.assert_allclose(read_record(path, columns={"t": "time"}).x, record["x"], rtol=1e-15)
    path.write_text("\n".join(["t,v,x", "s,V,furlong", *_rows(record)]) + "\n")
    with pytest.raises(DataFileError, match=r"units row \(s, V, furlong\), but 'furlong' is not"):
        read_record(path)  # a units row with a unit hystcomp does not know


def test_mat_and_npz_of_one_matrix_with_numbered_columns(tmp_path, record):
    matrix = np.column_stack([record["v"], record["t"], np.ones(300), record["x"]])
    mat, npz = tmp_path / "one.mat", tmp_path / "one.npz"
    scipy.io.savemat(mat, {"data": matrix})
    np.savez(npz, data=matrix.T)  # samples along the longer side, whichever it is
    for path in (mat, npz):
        _same(path, record, columns={"t": 2, "v": 1, "x": 4})
    with pytest.raises(DataFileError, match=r"one matrix 'data' \(300 x 4\).*t=1,v=2,x=3"):
        read_record(npz)


def test_duplicate_and_ambiguous_column_names_are_refused(tmp_path, record):
    path = tmp_path / "dup.csv"
    path.write_text("\n".join(["t,v,x,x", *(r + ",0" for r in _rows(record))]) + "\n")
    with pytest.raises(DataFileError, match=r"more than one column x .*own name"):
        read_record(path)
    path.write_text("\n".join(["t,v,x,X", *(r + ",0" for r in _rows(record))]) + "\n")
    with pytest.raises(DataFileError, match=r"more than one column X and x"):
        read_record(path)
    for bad in ({"v": 1, "x": 1}, {"v": "x", "x": "X"}):
        with pytest.raises(InvalidParameterError, match=r"for both 'v' and 'x'"):
            read_record(path, columns=bad)


def test_cli_refuses_duplicates_and_reads_lab_files(tmp_path, record):
    path = tmp_path / "dup.csv"
    path.write_text("\n".join(["t;v;x;x", *(r + ";0" for r in _rows(record, ";"))]) + "\n")
    runner = CliRunner()
    model = str(tmp_path / "m.json")
    result = runner.invoke(main, ["identify", str(path), "--model", "pi", "-o", model])
    assert result.exit_code == 2
    assert result.output.startswith("hystcomp: error: ")
    assert "more than one column x" in (result.output)
    result = runner.invoke(
        main, ["identify", str(path), "--model", "pi", "--columns", "v=1,x=1", "-o", model]
    )
    assert result.exit_code == 2
    assert "for both 'v' and 'x'" in result.output
    assert not os.path.exists(model)


def test_x_unit_converts_and_the_span_warns(tmp_path, record):
    metres = {**record, "x": record["x"] * 1e-6}
    path = tmp_path / "metres.csv"
    write_table(path, metres)
    rec = read_record(path, x_unit="m")
    np.testing.assert_allclose(rec.x, record["x"], rtol=1e-14)
    assert "looks like metres" in x_unit_warning(read_record(path).x, "metres.csv")
    assert "--x-unit nm" in x_unit_warning(record["x"] * 1000.0, "f")
    assert x_unit_warning(record["x"], "f") is None
    with pytest.raises(InvalidParameterError, match="'x_unit' parameter of read_table"):
        read_table(path, x_unit="inch")

    runner = CliRunner()
    model = tmp_path / "m.json"
    args = ["identify", str(path), "--model", "pi", "--operators", "4", "-o", str(model)]
    result = runner.invoke(main, args)
    assert result.exit_code == 0, result.output
    # (three quarters of a sine: the record also falls only once, a warning of its own)
    unit = "hystcomp: warning: the displacement in "
    warnings = [line for line in result.output.splitlines() if line.startswith(unit)]
    assert len(warnings) == 1
    assert "--x-unit m" in warnings[0]
    result = runner.invoke(main, [*args, "--x-unit", "m"])
    assert result.exit_code == 0
    assert unit not in result.output
    assert f"x {record['x'].min():.4g} .. {record['x'].max():.4g} µm" in result.output
    result = runner.invoke(main, [*args, "--quiet"])
    assert result.exit_code == 0
    assert unit not in result.output
    result = runner.invoke(main, [*args, "--x-unit", "yd"])
    assert result.exit_code == 2


def _npz_declaring(path, shape):
    """An NPZ whose member declares ``shape`` float64 values but holds few bytes."""
    header = {"descr": "<f8", "fortran_order": False, "shape": shape}
    with zipfile.ZipFile(path, "w") as archive, archive.open("v.npy", "w") as member:
        np.lib.format.write_array_header_1_0(member, header)
        member.write(b"\0" * 64)


def test_declared_sizes_are_refused_before_loading(tmp_path, monkeypatch):
    path = tmp_path / "huge.npz"
    _npz_declaring(path, (500_000_000,))
    with pytest.raises(DataFileError, match=r"'v' of shape \(500000000,\), more than 100000000"):
        read_table(path, ("v",), sample_rate=1.0)
    assert max_samples() == MAX_SAMPLES
    too_wide = r"shape \(200, 65\): 65 columns, more than the 64 .*Save only the signals' columns"
    _npz_declaring(path, (200, 65))  # the samples fit, the columns do not: said so
    with pytest.raises(DataFileError, match=too_wide):
        read_table(path, ("v",), sample_rate=1.0)
    scipy.io.savemat(tmp_path / "wide.mat", {"v": np.zeros((200, 65))})
    with pytest.raises(DataFileError, match=too_wide):
        read_table(tmp_path / "wide.mat", ("v",), sample_rate=1.0)
    monkeypatch.setenv("HYSTCOMP_MAX_SAMPLES", "100")
    _npz_declaring(path, (101, 1))
    with pytest.raises(DataFileError, match=r"more than 100 samples.*HYSTCOMP_MAX_SAMPLES"):
        read_table(path, ("v",), sample_rate=1.0)
    mat = tmp_path / "big.mat"
    scipy.io.savemat(mat, {"v": np.zeros(101)})
    with pytest.raises(DataFileError, match=r"'v' of shape \(1, 101\), more than 100"):
        read_table(mat, ("v",), sample_rate=1.0)
    csv = tmp_path / "long.csv"
    csv.write_text("v\n" + "1\n" * 101)
    with pytest.raises(DataFileError, match=r"more than 100 rows"):
        read_table(csv, ("v",), sample_rate=1.0)
    monkeypatch.setenv("HYSTCOMP_MAX_SAMPLES", "lots")
    with pytest.raises(DataFileError, match="HYSTCOMP_MAX_SAMPLES must be a whole number"):
        read_table(csv, ("v",), sample_rate=1.0)


def test_chunked_read_and_write_round_trip_across_chunks(tmp_path, rng, monkeypatch):
    import hystcomp.io._text as text
    from hystcomp.io._formats import read_raw

    monkeypatch.setattr(text, "CHUNK_BYTES", 1000)  # many chunks, rows cut anywhere
    monkeypatch.setattr(text, "SMALL_TABLE", 0)  # the compiled formatter, even for few rows
    n = 2000
    table = {
        "t": np.arange(n) / 3e3,
        "v": rng.standard_normal(n),
        "x": rng.standard_normal(n) * 1e-3,
        "w": rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n),
    }
    path = tmp_path / "long.csv"
    write_table(path, table)
    lines = path.read_text().splitlines()
    assert lines[0] == "t,v,x,w"
    assert lines[1:] == [",".join(repr(float(table[k][i])) for k in "tvxw") for i in range(n)]
    names, columns, _, _ = read_raw(path)
    assert names == list("tvxw")
    for key, column in zip(names, columns, strict=True):
        np.testing.assert_array_equal(column, table[key])
    path.write_text(path.read_text().replace("\n", "\n\n# a remark\n", 5))
    for key in "tvx":
        np.testing.assert_array_equal(read_table(path)[key], table[key])
    path.write_text("\n".join([*lines[:1500], "1,2", *lines[1500:]]) + "\n")
    # the row counted in the file's data rows across chunks (1-based, as elsewhere)
    with pytest.raises(DataFileError, match=r"numbers \(data row 1500 has 2 columns, not 4\)"):
        read_table(path)


_PEAK = (
    "import resource, sys\n"
    "import numpy as np\n"
    "from hystcomp.io.records import read_record, write_table\n"
    "import hystcomp.io._floattext  # numba, which the writer loads on first use\n"
    "def peak():  # MB; VmHWM, as ru_maxrss keeps the parent's peak across fork and exec\n"
    "    for line in open('/proc/self/status'):\n"
    "        if line.startswith('VmHWM:'):\n"
    "            return int(line.split()[1]) / 1024\n"
    "    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024\n"
)


def _growth(step: str, path) -> float:
    """Peak memory growth (MB) of ``step`` in a fresh process, over its imports."""
    code = _PEAK + "base = peak()\n" + step + "\nprint(peak() - base)\n"
    out = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True
    )
    return float(out.stdout)


def test_writing_and_reading_stay_in_bounded_memory(tmp_path):
    """Peak memory of writing, then reading, a 5e5-sample CSV (12 MB of values)."""
    path = tmp_path / "big.csv"
    make = "t = np.arange(500_000) / 2e4; table = {'t': t, 'v': np.sin(t), 'x': np.cos(t)}\n"
    # the table (12 MB), chunk buffers and loading the compiled formatter (~40 MB); writing
    # whole lists of Python floats and strings took about 190 MB
    assert _growth(make + "write_table(sys.argv[1], table)", path) < 100
    # the parsed table, which the record keeps (12 MB), pandas' buffers for a chunk and
    # loading pandas (~40 MB)
    assert _growth("rec = read_record(sys.argv[1])", path) < 100


def test_the_unit_warning_asks_to_check_a_unit_the_user_gave_instead_of_suggesting_another():
    given = x_unit_warning([0.0, 3.7e7], "rec.csv", "m")
    assert "read in m as --x-unit says" in given
    assert "give --x-unit" not in given
    assert "give --x-unit nm" in x_unit_warning([0.0, 3.7e7], "rec.csv")
    assert x_unit_warning([0.0, 37.0], "rec.csv", "m") is None


def test_files_that_are_not_npz_or_hold_nothing_are_named_so(tmp_path):
    text = tmp_path / "text.npz"
    text.write_text("t,v,x\n0,1,2\n")  # numpy would speak of pickled data and allow_pickle
    single = tmp_path / "single.npz"
    with single.open("wb") as file:
        np.save(file, np.arange(5.0))
    empty_npz, empty_mat = tmp_path / "empty.npz", tmp_path / "empty.mat"
    np.savez(empty_npz)
    scipy.io.savemat(empty_mat, {})
    cases = [
        (text, r"'.*text\.npz' is not a NumPy \.npz file: it is not a zip archive"),
        (single, r"it holds a single \.npy array, not named arrays"),
        (empty_npz, r"'.*empty\.npz' holds no columns"),
        (empty_mat, r"'.*empty\.mat' holds no columns"),
    ]
    for path, message in cases:
        with pytest.raises(DataFileError, match=message) as caught:
            read_record(path)
        assert "pickle" not in str(caught.value)


def test_optional_columns_are_read_when_present(tmp_path, record):
    path = tmp_path / "rec.csv"
    write_table(path, record)
    table = read_table(path, ("v",), optional=("x",))
    np.testing.assert_array_equal(table["x"], read_table(path)["x"])
    write_table(tmp_path / "v.csv", {"t": record["t"], "v": record["v"]})
    assert set(read_table(tmp_path / "v.csv", ("v",), optional=("x",))) == {"t", "v"}
    with pytest.raises(InvalidParameterError, match="'keys' and 'optional'"):
        read_table(path, ("v",), optional=("v",))


def test_one_column_is_not_read_as_two_signals(tmp_path, record):
    path = tmp_path / "rec.csv"
    write_table(path, record)
    with pytest.raises(DataFileError, match=r"read both as 'v'.*and as 'x'"):
        read_table(path, columns={"x": "v"})


def test_a_headerless_table_with_a_leading_separator_keeps_its_column_numbers(tmp_path, record):
    """``,0,-1.617,0`` as some acquisition scripts write it: the empty first column keeps
    its number, so the numbers a spreadsheet shows (t=2, v=4, x=3) name the columns."""
    path = tmp_path / "acquisition.csv"
    columns = (record[k].tolist() for k in "tvx")
    rows = [f",{t!r},{x!r},{v!r}" for t, v, x in zip(*columns, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    _same(path, record, columns="t=2,v=4,x=3")
    out = tmp_path / "m.json"  # the same spec on the command line
    cli = CliRunner().invoke(
        main,
        ["identify", str(path), "--model", "pi", "--columns", "t=2,v=4,x=3", "-o", str(out)],
    )
    assert cli.exit_code == 0, cli.output
    assert out.is_file()
    # a row of other length is still refused, with its data row
    path.write_text("\n".join([*rows[:4], ",1,2", *rows[4:]]) + "\n")
    with pytest.raises(DataFileError, match=r"data row 5 has 3 columns, not 4"):
        read_record(path, columns="t=2,v=4,x=3")


def test_decimal_commas_in_one_headerless_column_are_read_or_refused_never_misread(tmp_path):
    x = np.array([0.046, 0.067, 0.5, 1.25, 0.003])
    path = tmp_path / "x.csv"
    # "0,046": a leading zero in the second field, which no integer column writes
    path.write_text("".join(repr(value).replace(".", ",") + "\n" for value in x.tolist()))
    got = read_table(path, ("x",), columns="x=1", sample_rate=20_000.0)["x"]
    np.testing.assert_array_equal(got, x)
    result = CliRunner().invoke(
        main,
        ["compensate", str(_model(tmp_path)), str(path), "--columns", "x=1", "--fs", "20000",
         "-o", str(tmp_path / "v.csv")],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    written = (tmp_path / "v.csv").read_text().splitlines()
    assert written[0] == "t,v,x_ref"
    assert [float(line.split(",")[2]) for line in written[1:]] == x.tolist()  # not 0, 0, 0, 1
    # with a header of one name: one column, whatever the digits
    path.write_text("x\n1,5\n2,25\n3,5\n")
    one = read_table(path, ("x",), sample_rate=1.0)["x"]
    np.testing.assert_array_equal(one, [1.5, 2.25, 3.5])
    # a header of two names: two columns of integers
    path.write_text("t,x\n1,5\n2,25\n3,5\n")
    np.testing.assert_array_equal(read_table(path, ("x",))["x"], [5.0, 25.0, 5.0])
    # neither: the two readings differ, so it is refused with the fix
    path.write_text("1,5\n2,25\n3,5\n")
    with pytest.raises(DataFileError, match=r"two whole numbers split by a comma.*header row"):
        read_table(path, ("x",), columns={"x": 1}, sample_rate=1.0)


def _model(folder):
    from hystcomp import presets, save_model

    path = folder / "model.json"
    save_model(presets.paper_mpi(), path)
    return path


def test_a_first_line_longer_than_the_head_is_read_or_named(tmp_path, monkeypatch):
    import hystcomp.io._text as text

    # (the head and the longest line made small, so that a small file shows what a header
    # of 1e5 columns does with the real sizes, 64 KiB and 1 MiB)
    monkeypatch.setattr(text, "HEAD_BYTES", 512)
    monkeypatch.setattr(text, "MAX_LINE_BYTES", 8192)
    wide = tmp_path / "wide.csv"
    names = ["t", "v", "x", *(f"c{i}" for i in range(300))]  # a header over the head
    values = np.arange(len(names), dtype=float)
    rows = [",".join(map(repr, (values + k).tolist())) for k in (0, 1)]
    wide.write_text("\n".join([",".join(names), *rows]) + "\n")
    assert len(wide.read_text().splitlines()[0]) > text.HEAD_BYTES
    table = read_table(wide, ("v", "x"))
    np.testing.assert_array_equal(table["x"], [2.0, 3.0])
    along = tmp_path / "along.csv"
    along.write_text(",".join(repr(float(k)) for k in range(3000)) + "\n")  # along a line
    with pytest.raises(DataFileError, match=r"first line of more than \d+ bytes.*transpose"):
        read_table(along, ("x",), columns={"x": 1}, sample_rate=1.0)


def test_a_pandas_without_the_reader_engine_reads_the_same_through_a_dataframe(
    tmp_path, record, monkeypatch
):
    import pandas as pd

    real = pd.read_csv

    class Reader:  # what a pandas whose reader has no engine to ask would hand over
        def __init__(self, *args, **kwargs):
            self._reader = real(*args, **kwargs)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self._reader.close()

        def read(self):
            return self._reader.read()

    path = tmp_path / "rec.csv"
    write_table(path, record)
    monkeypatch.setattr(pd, "read_csv", Reader)
    _same(path, record)
