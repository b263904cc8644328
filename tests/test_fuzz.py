"""Fuzzing the boundaries: any input gives a valid object or a clean hystcomp error.

Never another exception (warnings are errors in this test suite, so a numpy warning
counts too), and a model or compensator that is accepted never outputs NaN or inf.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import event, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import hystcomp
from hystcomp import io as model_io
from hystcomp import presets
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.data import read_record, read_table
from hystcomp.errors import HystcompError, NotInvertibleError
from tests.conftest import examples

# Boundary fuzzing needs many examples to reach the odd corners, and each one is cheap.
FUZZ = settings(max_examples=examples(4))


def _scratch(data: bytes, suffix: str) -> Path:
    fd, name = tempfile.mkstemp(suffix=suffix)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    return Path(name)


def _read(data: bytes, suffix: str, **kwargs):
    """read_table on ``data`` saved as a file: the table, or None after a clean error."""
    path = _scratch(data, suffix)
    try:
        return read_table(path, ("v", "x"), **kwargs)
    except HystcompError:
        return None
    finally:
        path.unlink()


def _check_table(table) -> None:
    if table is None:
        return
    assert len({a.size for a in table.values()}) == 1
    assert all(np.all(np.isfinite(a)) for a in table.values())
    assert np.all(np.diff(table["t"]) > 0)
    assert np.all(np.abs(table["v"]) <= MAX_MAGNITUDE)


READ_OPTIONS = st.sampled_from(
    [{}, {"sample_rate": 100.0}, {"columns": {"v": 1, "x": 2}, "sample_rate": 10.0}]
)


CSV_ALPHABET = "0123456789.,-+eE \t\n#tvxnaifINF\"';\r\x00"
SPECIAL = st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -2e12, 5e-324, 0.0])


@st.composite
def tables(draw, min_size=0, special=True):
    """Columns t, v, x of a random length, t increasing; sometimes one special value."""
    n = draw(st.integers(min_size, 12))
    steps = draw(st.lists(st.floats(1e-4, 1.0), min_size=n, max_size=n))
    table = {"t": np.cumsum(steps)}
    for key in "vx":
        table[key] = np.array(draw(st.lists(st.floats(-200, 200), min_size=n, max_size=n)))
    if special and n and draw(st.booleans()):
        key, k = draw(st.sampled_from("tvx")), draw(st.integers(0, n - 1))
        table[key][k] = draw(SPECIAL)
    return table


def _read_record(data: bytes, suffix: str):
    """read_record on ``data`` saved as a file: the record, or None after a clean error."""
    path = _scratch(data, suffix)
    try:
        return read_record(path)
    except HystcompError:
        return None
    finally:
        path.unlink()


def _check_record(rec) -> None:
    n = len(rec)
    assert n >= 2
    assert rec.t.size == rec.v.size == rec.x.size == n
    for arr in (rec.t, rec.v, rec.x):
        assert arr.dtype == np.float64
        assert np.all(np.isfinite(arr))
    assert np.all(np.abs(rec.v) <= MAX_MAGNITUDE)
    assert np.all(np.abs(rec.x) <= MAX_MAGNITUDE)
    assert np.all(np.diff(rec.t) > 0)
    assert np.ptp(rec.v) > 0
    assert 0 < rec.sample_rate < np.inf


@st.composite
def valid_files(draw):
    """A valid record as the bytes of a ``.csv``, ``.txt``, ``.dat`` or ``.npz`` file."""
    table = draw(tables(min_size=2, special=False))
    table["v"][0] += 1.0  # an input that varies (read_record refuses a constant one)
    suffix = draw(st.sampled_from([".csv", ".txt", ".dat", ".npz"]))
    if suffix == ".npz":
        buffer = io.BytesIO()
        draw(st.sampled_from([np.savez, np.savez_compressed]))(buffer, **table)
        return buffer.getvalue(), suffix
    keys = draw(st.permutations("tvx"))
    sep = "," if suffix == ".csv" else draw(st.sampled_from([" ", "\t", "  "]))
    end = draw(st.sampled_from(["\n", "\r\n"]))
    rows = np.column_stack([table[k] for k in keys]).tolist()
    lines = [sep.join(keys), *(sep.join(map(repr, row)) for row in rows)]
    return (end.join(lines) + end * draw(st.integers(0, 2))).encode("ascii"), suffix


MUTATIONS = st.lists(  # overwrite, insert or delete a few bytes, or cut the file short
    st.tuples(
        st.sampled_from(["flip", "insert", "delete", "truncate"]),
        st.integers(0, 10**6),
        st.one_of(  # mostly digits: a corrupted value that may still parse
            st.text("0123456789", min_size=1, max_size=3),
            st.text("0123456789", min_size=1, max_size=3),
            st.text(CSV_ALPHABET, min_size=1, max_size=6),
            st.binary(min_size=1, max_size=6),
        ),
    ),
    max_size=3,
)


def _mutate(data: bytes, mutations) -> bytes:
    out = bytearray(data)
    for op, where, chunk in mutations:
        chunk = chunk.encode("utf-8") if isinstance(chunk, str) else chunk
        k = where % (len(out) + 1)
        if op == "flip":
            out[k : k + len(chunk)] = chunk
        elif op == "insert":
            out[k:k] = chunk
        elif op == "delete":
            del out[k : k + len(chunk)]
        else:
            del out[k:]
    return bytes(out)


def test_valid_then_mutated_data_files():
    """Valid files with up to three random corruptions: a clean error, or a valid record.

    Most inputs are close enough to valid that a share of them is read, so the checks on
    accepted records really run (counted below), unlike random bytes, which are refused.
    """
    seen = []  # (suffix, mutated, accepted) per example

    @settings(max_examples=examples(4))  # each example is one cheap read
    @given(file=valid_files(), mutations=MUTATIONS)
    def run(file, mutations):
        data, suffix = file
        mutated = _mutate(data, mutations)
        rec = _read_record(mutated, suffix)
        seen.append((suffix, mutated != data, rec is not None))
        event(f"{suffix} {'mutated' if mutated != data else 'valid'} {rec is not None}")
        if rec is not None:
            _check_record(rec)
        elif mutated == data:
            raise AssertionError(f"a valid {suffix} file was refused")

    run()
    mutated = [ok for _, changed, ok in seen if changed]
    assert {suffix for suffix, _, _ in seen} == {".csv", ".txt", ".dat", ".npz"}
    assert np.mean([ok for _, _, ok in seen]) > 0.4, seen
    assert len(mutated) > 0.3 * len(seen)
    assert np.mean(mutated) > 0.15, seen  # corrupted files that are still read, and checked


@given(data=st.binary(max_size=400), suffix=st.sampled_from([".csv", ".dat", ".npz"]))
def test_random_bytes(data, suffix):
    """Random bytes, also behind the magic numbers of a zip and an npy file: never a crash."""
    for prefix in (b"", b"PK\x03\x04", b"\x93NUMPY\x01\x00"):
        _check_table(_read(prefix + data, suffix))


@FUZZ
@given(
    table=tables(),
    garbage=st.text(alphabet=CSV_ALPHABET, max_size=40),
    where=st.integers(0, 10**4),
    header=st.sampled_from(["t,v,x\n", "", "v x t\n", "t,v\n"]),
    suffix=st.sampled_from([".csv", ".txt"]),
    options=READ_OPTIONS,
)
def test_random_csv_like_text(table, garbage, where, header, suffix, options):
    rows = np.column_stack([table["t"], table["v"], table["x"]]).tolist()
    text = header + "".join(",".join(map(repr, row)) + "\n" for row in rows)
    cut = where % (len(text) + 1)
    for candidate in (text, text[:cut] + garbage + text[cut:]):
        _check_table(_read(candidate.encode("utf-8"), suffix, **options))


ARRAYS = hnp.arrays(
    dtype=st.sampled_from(
        [np.float64, np.float32, np.int8, np.uint64, np.bool_, np.complex128, np.dtype("U2")]
    ),
    shape=hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=5),
)


@FUZZ
@given(
    table=tables(),
    others=st.dictionaries(st.sampled_from(["t", "v", "x", "y"]), ARRAYS, max_size=2),
    objects=st.booleans(),
    flips=st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=2),
    options=READ_OPTIONS,
)
def test_random_npz_contents(table, others, objects, flips, options):
    arrays = {**table, **others}
    if objects:  # saved with pickle by numpy; must be refused, never unpickled
        arrays["v"] = np.array([1.0, None, "a"], dtype=object)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    data = bytearray(buffer.getvalue())
    for where, value in flips:
        data[where % len(data)] = value
    _check_table(_read(bytes(data), ".npz", **options))


def test_npz_members_that_are_not_arrays():
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("v.npy", b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'shape': (10**12,)}")
        archive.writestr("x.npy", b"not an array")
    assert _read(buffer.getvalue(), ".npz") is None


def test_corrupt_mat_files():
    """A valid MAT file with a few bytes overwritten past its 128-byte header.

    Few examples: each read runs scipy in a child process (a fraction of a second). A flip
    inside the numbers keeps the file readable, so some are read and checked (counted).
    """
    buffer = io.BytesIO()
    table = {"t": np.arange(1.0, 5.0), "v": np.arange(4.0), "x": np.arange(4.0)}
    scipy.io.savemat(buffer, table)
    valid = buffer.getvalue()
    seen = []

    @settings(max_examples=examples(0.2))
    @given(
        flips=st.lists(
            st.tuples(st.integers(0, 10**4), st.integers(0, 255)), min_size=1, max_size=2
        )
    )
    def run(flips):
        data = bytearray(valid)
        for where, value in flips:
            data[128 + where % (len(data) - 128)] = value
        result = _read(bytes(data), ".mat")
        seen.append(result is not None)
        _check_table(result)

    run()
    assert any(seen)


# Model construction ---------------------------------------------------------------------

NUMBERS = st.one_of(  # mostly ordinary: one_of picks each branch equally often
    st.floats(-1e3, 1e3),
    st.floats(-1e3, 1e3),
    st.floats(-1e3, 1e3),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**20), 10**20),
)
VECTORS = st.one_of(
    st.lists(NUMBERS, max_size=6), st.lists(st.floats(0.0, 200.0), min_size=1, max_size=6)
)


def _vector(draw, n):
    """Usually ``n`` ordinary numbers; sometimes another length or odd entries."""
    if draw(st.integers(0, 9)) == 0:
        return draw(VECTORS)
    return draw(st.lists(NUMBERS, min_size=n, max_size=n))


def _thresholds(draw, n):
    if draw(st.integers(0, 9)) == 0:
        return draw(VECTORS)
    big = draw(st.sampled_from([1e3, 1e3, 1e13]))
    steps = draw(st.lists(st.floats(1e-6, big), min_size=n - 1, max_size=n - 1))
    return np.cumsum([0.0, *steps]).tolist()  # valid: 0, then increasing


@st.composite
def parameters(draw, kind):
    n, m = draw(st.integers(1, 6)), draw(st.integers(1, 6))
    params = {"thresholds": _thresholds(draw, n), "weights": _vector(draw, n)}
    if kind == "mpi":
        params["deadzone_thresholds"] = _thresholds(draw, m)
        params["deadzone_weights"] = _vector(draw, m)
    for name in ("input_offset", "output_offset"):
        if draw(st.booleans()):
            params[name] = draw(NUMBERS)
    if draw(st.booleans()):
        params["voltage_range"] = sorted(draw(st.lists(NUMBERS, min_size=2, max_size=2)))
    if draw(st.booleans()):
        params["initial_state"] = _vector(draw, n)
    return params


SIGNALS = st.lists(st.floats(-MAX_MAGNITUDE, MAX_MAGNITUDE), min_size=1, max_size=30)


def _exercise(model, signal) -> None:
    """An accepted model gives finite outputs; its inverse stays finite and in range."""
    assert np.all(np.isfinite(model.simulate(signal)))
    try:
        comp = model.inverse()
    except NotInvertibleError:
        return
    lo, hi = comp.voltage_range
    for v in (comp.simulate(signal), comp.stepper().step_block(signal)):
        assert np.all(np.isfinite(v))
        assert np.all((v >= lo) & (v <= hi))


@FUZZ
@given(data=st.data(), kind=st.sampled_from(["pi", "mpi"]), signal=SIGNALS)
def test_from_parameters_with_random_parameters(data, kind, signal):
    cls = model_io.MODEL_KINDS[kind]
    try:
        model = cls.from_parameters(**data.draw(parameters(kind)))
    except HystcompError:
        return
    _exercise(model, signal)


JSON = st.recursive(
    st.none() | st.booleans() | NUMBERS | st.text(max_size=5),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4)
    ),
    max_leaves=12,
)


def _paths(doc, prefix=()):
    yield prefix
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from _paths(value, (*prefix, key))
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield from _paths(value, (*prefix, i))


def _load_text(text: str):
    path = _scratch(text.encode("utf-8"), ".json")
    try:
        return hystcomp.load_model(path)
    except HystcompError:
        return None
    finally:
        path.unlink()


@FUZZ
@given(doc=JSON)
def test_loading_random_json_documents(doc):
    for candidate in (doc, {"format": "hystcomp-model", "version": 1, "kind": "pi", **(
        doc if isinstance(doc, dict) else {"parameters": doc})}):  # fmt: skip
        model = _load_text(json.dumps(candidate, allow_nan=True))
        if model is not None:
            _exercise(model, np.linspace(-200.0, 200.0, 7))


BASE_DOCUMENTS = [model_io.model_to_dict(m) for m in (presets.paper_pi(), presets.paper_mpi())]


@FUZZ
@given(
    which=st.sampled_from([0, 1]),
    choice=st.integers(0, 10**6),
    value=st.one_of(NUMBERS, st.lists(NUMBERS, max_size=20), JSON),
    delete=st.booleans(),
    signal=SIGNALS,
)
def test_loading_mutated_model_files(which, choice, value, delete, signal):
    doc = json.loads(json.dumps(BASE_DOCUMENTS[which]))
    paths = list(_paths(doc))[1:]
    path = paths[choice % len(paths)]
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    if delete and isinstance(parent, dict):
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    model = _load_text(json.dumps(doc, allow_nan=True))
    if model is not None:
        _exercise(model, signal)


@pytest.mark.parametrize("kind", ["pi", "mpi"])
def test_exercise_is_not_vacuous(kind):
    """The fuzzing checks run on real models too: a valid document is loaded and exercised."""
    model = _load_text(json.dumps(BASE_DOCUMENTS[kind == "mpi"]))
    assert model is not None
    assert model.kind == kind
    _exercise(model, np.linspace(-1e6, 1e6, 11))
