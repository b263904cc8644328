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
from hystcomp import presets
from hystcomp._hyperparameters import MAX_DEGREE
from hystcomp._kernels.preisach import monomial_exponents, n_monomials
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.codegen import generate_c
from hystcomp.errors import (
    HystcompError,
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
    NotInvertibleError,
)
from hystcomp.io import models as model_io
from hystcomp.io.records import read_record, read_table
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.preisach import Preisach
from hystcomp.workflows.pair import predicted_worse
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
    table["v"][0] = table["v"].max() + 1.0  # an input that varies (not refused as constant)
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


MUTATIONS = st.lists(  # change a digit, overwrite, insert or delete bytes, or cut the file
    st.tuples(
        st.sampled_from(["digit", "digit", "flip", "insert", "delete", "truncate"]),
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
        digits = [i for i, byte in enumerate(out) if 48 <= byte <= 57]
        if op == "digit" and digits:  # another value, often still a valid file
            out[digits[where % len(digits)]] = 48 + chunk[0] % 10
        elif op == "flip":
            out[k : k + len(chunk)] = chunk
        elif op == "insert":
            out[k:k] = chunk
        elif op == "delete":
            del out[k : k + len(chunk)]
        elif op == "truncate":
            del out[k:]
    return bytes(out)


def test_valid_then_mutated_data_files():
    """Valid files with up to three random corruptions: a clean error, or a valid record.

    Most inputs are close enough to valid that a share of them is read, so the checks on
    accepted records really run (counted below), unlike random bytes, which are refused.
    """
    seen = []  # (suffix, mutated, accepted) per example

    @settings(max_examples=examples(3))  # each example is one cheap read
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
    assert np.mean(mutated) > 0.1, seen  # corrupted files that are still read, and checked


@FUZZ
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
    if isinstance(model, LinearDynamics):
        _exercise_dynamics(model, signal)
        return
    if isinstance(model, HammersteinModel):  # both parts, each as it would be alone
        predicted_worse(model, np.clip(signal, -1e3, 1e3), model.sample_rate)  # its report
        _exercise(model.hysteresis, signal)
        _exercise_dynamics(model.dynamics, signal, model.hysteresis)
        return
    covered = model.covered_range()  # from the fit report, which no check has read
    assert covered is None or (np.all(np.isfinite(covered)) and covered[0] < covered[1])
    if isinstance(model, Preisach):
        _exercise_preisach(model, signal, np.linspace(-1.5, 1.5, 7), [(2, np.nan)])
        return
    assert np.all(np.isfinite(model.simulate(signal)))
    try:
        comp = model.inverse()
    except NotInvertibleError:
        return
    lo, hi = comp.voltage_range
    for v in (comp.simulate(signal), comp.stepper().step_block(signal)):
        assert np.all(np.isfinite(v))
        assert np.all((v >= lo) & (v <= hi))


def _exercise_dynamics(model, signal, hysteresis=None) -> None:
    """Accepted linear dynamics: a finite response, and a compensator in series with them
    (as a pair, with ``hysteresis`` or the paper's MPI model) whose voltage is finite and in
    range, in Python and as C (or a clean refusal)."""
    assert np.all(np.isfinite(model.simulate(signal)))
    try:
        comp = HammersteinModel(hysteresis or presets.paper_mpi(), model).inverse()
    except HystcompError:  # e.g. dynamics the inverse cannot be designed for
        return
    lo, hi = comp.voltage_range
    reference = np.concatenate([np.linspace(-10.0, 50.0, 60), np.clip(signal, -1e3, 1e3)])
    run = comp.run(reference)
    assert np.array_equal(run.v, comp.simulate(reference))
    assert np.all(np.isfinite(run.v))
    assert np.all((run.v >= lo) & (run.v <= hi))
    assert 0 <= run.clamped <= reference.size
    header, _ = generate_c(comp)  # the look-ahead of the C is the compensator's
    assert f"#define HYSTCOMP_COMPENSATOR_PREVIEW {comp.preview}\n" in header


@FUZZ
@given(data=st.data(), kind=st.sampled_from(["pi", "mpi"]), signal=SIGNALS)
def test_from_parameters_with_random_parameters(data, kind, signal):
    cls = model_io.MODEL_KINDS[kind]
    try:
        model = cls.from_parameters(**data.draw(parameters(kind)))
    except HystcompError:
        return
    _exercise(model, signal)


# Preisach models ------------------------------------------------------------------------

ORDINARY = st.one_of(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3), st.floats(-1e12, 1e12))


def _odd(draw) -> bool:
    """True once in 8 draws: when to try an invalid value instead of an ordinary one."""
    return draw(st.integers(0, 7)) == 0


def _entries(draw, n):
    """``n`` ordinary numbers; sometimes another length or odd entries."""
    if _odd(draw):
        return draw(st.one_of(VECTORS, st.lists(NUMBERS, min_size=n, max_size=n)))
    return draw(st.lists(ORDINARY, min_size=n, max_size=n))


def _table(draw):
    """Usually a square table; sometimes NaN above the diagonal (not read), or another shape."""
    n = draw(st.integers(2, 6))
    if _odd(draw):  # too small, ragged, flat, deeper, or with odd entries
        rows = [[[0.0]], [[0.0] * n, [0.0] * (n + 1)], [1.0] * n, [[[0.0] * n] * n]]
        return draw(st.sampled_from([*rows, [_entries(draw, n) for _ in range(n)]]))
    table = np.array([draw(st.lists(ORDINARY, min_size=n, max_size=n)) for _ in range(n)])
    if draw(st.booleans()):
        table[np.triu_indices(n, 1)] = draw(st.sampled_from([np.nan, np.inf, 1e300]))
    return table.tolist()


@st.composite
def preisach_parameters(draw):
    """``Preisach.from_parameters`` arguments: usually valid, sometimes odd."""
    params = {}
    which = draw(st.sampled_from(["theta", "table"]))
    if _odd(draw):
        which = draw(st.sampled_from(["both", "neither"]))
    if which in ("theta", "both"):
        degree = draw(st.integers(1, MAX_DEGREE + 1))
        params["theta"] = _entries(draw, n_monomials(degree))
    if which in ("table", "both"):
        params["table"] = _table(draw)
    if draw(st.booleans()):
        params["output_offset"] = draw(NUMBERS if _odd(draw) else ORDINARY)
    if draw(st.integers(0, 3)):
        pair = draw(st.lists(NUMBERS if _odd(draw) else ORDINARY, min_size=2, max_size=2))
        params["voltage_range"] = pair if _odd(draw) else sorted(pair)
    if draw(st.booleans()):  # a small memory exercises the wipe-out of the innermost loop
        odd = st.one_of(st.integers(-1, 2), NUMBERS, st.booleans())
        params["max_extrema"] = draw(odd if _odd(draw) else st.integers(3, 2000))
    return params


def _everett_bound(model) -> float:
    """A bound of ``|X|`` on the plane: ``sum |theta_k| span**(i+j)``, or ``max |table|``."""
    if model.theta_ is None:
        return float(np.max(np.abs(model.table_)))
    lo, hi = model.voltage_range_
    powers = np.array([i + j for i, j in monomial_exponents(model.degree)], dtype=float)
    return float(np.sum(np.abs(model.theta_) * (hi - lo) ** powers))


def _falls(model) -> bool:
    """Whether X, on the table's nodes or 129 nodes per axis, falls from one node to the
    next along alpha, rises along beta (beyond rounding), or X(v_max, v_min) <= 0."""
    lo, hi = model.voltage_range_
    u = np.linspace(lo, hi, 129 if model.table_ is None else model.table_.shape[0])
    X = np.tril(model.everett_function(u[:, None], u[None, :]))
    tol = 1e-9 * np.abs(X).max()
    falls = [X[-1, 0] <= 0.0]
    for i in range(u.size):
        for j in range(i + 1):
            if i + 1 < u.size:
                falls.append(X[i + 1, j] < X[i, j] - tol)
            if j + 1 <= i:
                falls.append(X[i, j + 1] > X[i, j] + tol)
    return any(falls)


HOLES = st.lists(  # where to insert a non-finite sample into a stream, and which one
    st.tuples(st.integers(0, 100), st.sampled_from([np.nan, np.inf, -np.inf])), max_size=4
)


def _check_stream(system, signal, expected, holes, rest) -> None:
    """The stepper on ``signal`` with non-finite samples inserted: bit for bit the batch run
    on the finite samples; each non-finite one holds the last output (``rest`` at first)
    and is counted."""
    u = list(signal)
    for where, value in holes:
        u.insert(where % (len(u) + 1), value)
    u = np.array(u)
    hole = ~np.isfinite(u)
    stepper = system.stepper()
    assert stepper.last_output == rest
    out = stepper.step_block(u)
    np.testing.assert_array_equal(out[~hole], expected)
    held = np.concatenate([[rest], out[:-1]])
    np.testing.assert_array_equal(out[hole], held[hole])
    assert stepper.nonfinite_count == hole.sum()
    if hole.any():  # a batch run refuses them instead (documented on simulate)
        with pytest.raises(InvalidSignalError, match="must be finite"):
            system.simulate(u)


def _exercise_preisach(model, signal, reference, holes=(), options=None) -> None:
    """An accepted Preisach model and its compensators: finite, bounded, in range.

    ``signal`` are voltages (V); ``reference`` are fractions of the model's output range
    turned into displacements (µm); ``options`` are more keyword arguments of ``inverse``
    (which may be refused cleanly).
    """
    x0 = model.output_offset_
    bound = _everett_bound(model)
    x = model.simulate(signal)
    assert np.all(np.isfinite(x))
    # eqs. (3)-(4): x - x_0 sums at most one X per stored extremum, and one more
    limit = (len(signal) + 2) * bound * (1 + 1e-9) + 2 * np.spacing(abs(x0))  # x0 + H rounds
    assert np.all(np.abs(x - x0) <= limit), (x, bound)
    _check_stream(model, signal, x, holes, rest=x0)
    ref = np.clip(x0 + bound * np.asarray(reference), -MAX_MAGNITUDE, MAX_MAGNITUDE)
    compensators = []
    for kwargs in ({}, {"method": "exact"}, options):
        if kwargs is None:
            continue
        try:
            compensators.append(model.inverse(**kwargs))
        except NotInvertibleError:  # only a model whose major loop or a branch falls
            assert _falls(model)
        except HystcompError:  # the defaults are refused only for a model without an inverse
            assert kwargs
    v_min = model.voltage_range_[0]
    for comp in compensators:
        low, high = comp.voltage_range
        assert model.voltage_range_[0] <= low < high <= model.voltage_range_[1]
        for r in (ref, signal):
            v = comp.simulate(r)
            assert np.all(np.isfinite(v))
            assert np.all((v >= low) & (v <= high))
            ulp = 2 * np.spacing(np.max(np.abs(v)))  # v[k-1] + step rounds to v's precision
            assert np.all(np.abs(np.diff(v)) <= comp.max_step * (1 + 1e-9) + ulp)
            _check_stream(comp, r, v, holes, rest=min(max(v_min, low), high))


def _inverse_options(draw, model):
    """Keyword arguments of ``Preisach.inverse``: usually valid, sometimes not."""
    lo, hi = model.voltage_range_
    options = {}
    if draw(st.booleans()):
        options["method"] = draw(st.sampled_from(["multiplicative", "exact", "newton", None]))
    if draw(st.integers(0, 3)) == 0:
        options["rho"] = draw(st.one_of(st.floats(1e-6, 1e3), NUMBERS))
    if draw(st.booleans()):
        options["slew_rate"] = draw(st.one_of(st.floats(1e-3, 1e7), NUMBERS))
    if draw(st.booleans()):
        a, b = sorted(draw(st.lists(st.floats(-0.1, 1.0), min_size=2, max_size=2)))
        options["voltage_range"] = (lo + a * (hi - lo), lo + b * (hi - lo))
    return options


@st.composite
def plane_signals(draw, model):
    """Voltages mostly on the Preisach plane, some beyond it (saturation)."""
    lo, hi = model.voltage_range_
    u = np.array(draw(st.lists(st.floats(-0.3, 1.3), min_size=1, max_size=30)))
    return np.clip(lo + u * (hi - lo), -MAX_MAGNITUDE, MAX_MAGNITUDE)


FRACTIONS = st.lists(st.floats(-1.5, 1.5), min_size=1, max_size=30)


def test_preisach_from_random_parameters():
    """Any parameters give a model that works (output bounded by eqs. 3-4, compensators
    in range, non-finite samples held) or a clean error; enough of them are accepted."""
    accepted = []

    @settings(max_examples=examples(3))  # each builds a model and three compensators
    @given(data=st.data(), reference=FRACTIONS, holes=HOLES)
    def run(data, reference, holes):
        params = data.draw(preisach_parameters())
        try:
            model = Preisach.from_parameters(**params)
        except HystcompError:
            accepted.append(False)
            return
        accepted.append(model.everett)
        signal = data.draw(st.one_of(plane_signals(model), SIGNALS))
        options = _inverse_options(data.draw, model)
        _exercise_preisach(model, signal, reference, holes, options)

    run()
    kinds = [kind for kind in accepted if kind]
    assert len(kinds) > 0.3 * len(accepted)
    assert {"polynomial", "table"} <= set(kinds)
    assert min(kinds.count("polynomial"), kinds.count("table")) > 0.1 * len(accepted)


def test_preisach_with_non_finite_upper_table_and_tiny_memory():
    """Only the lower triangle of a table is read, and a memory of 3 extrema still works."""
    table = [[0.0, np.nan], [2.0, 0.0]]
    model = Preisach.from_parameters(table=table, voltage_range=(0.0, 1.0), max_extrema=3)
    v = [0.0, 1.0, 0.2, 0.8, 0.4, 0.6, 0.5, 1.0, 0.0]
    _exercise_preisach(model, v, [0.0, 0.5, 1.0, 0.2], [(3, np.nan)], {"slew_rate": 10.0})


def test_preisach_table_beyond_the_magnitude_bound_is_refused():
    # accepted before, and gave inf - inf = NaN outputs
    for value in (1.5e308, -1e13):
        with pytest.raises(InvalidParameterError, match=r"'table'.*at most 1e\+12"):
            Preisach.from_parameters(table=[[0.0, 0.0], [value, 0.0]], voltage_range=(0, 1))
    with pytest.raises(InvalidTypeError, match="'table'"):  # was read as a number
        Preisach.from_parameters(table=[["0", "0"], ["1", "0"]])


def test_preisach_file_whose_degree_does_not_match_theta_is_refused():
    # was loaded, then simulate raised a bare ValueError from the coefficient matrix
    doc = model_io.model_to_dict(presets.paper_preisach())
    doc["parameters"]["theta"] = [0.0, 0.3]  # degree 1, but "degree": 3 stays
    assert _load_text(json.dumps(doc)) is None
    doc["hyperparameters"]["degree"] = 1
    assert _load_text(json.dumps(doc)).simulate([0.0, 10.0]).tolist() == [0.0, 3.0]
    doc["hyperparameters"]["max_extrema"] = 0  # was loaded, then refused by simulate
    assert _load_text(json.dumps(doc)) is None


@pytest.mark.parametrize("method", ["multiplicative", "exact"])
def test_preisach_compensator_rests_inside_a_narrower_range(method):
    # before the first finite sample it held v_min, outside voltage_range=(10, 100)
    comp = presets.paper_preisach().inverse(method=method, voltage_range=(10.0, 100.0))
    stepper = comp.stepper()
    assert stepper.last_output == 10.0
    assert stepper.step(np.nan) == 10.0
    _, source = generate_c(comp)
    assert "s->last = 10.0;" in source
    assert "s->last = 0.0;" not in source


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
@given(doc=JSON, kind=st.sampled_from(sorted(model_io.MODEL_KINDS)))
def test_loading_random_json_documents(doc, kind):
    for candidate in (doc, {"format": "hystcomp-model", "version": 1, "kind": kind, **(
        doc if isinstance(doc, dict) else {"parameters": doc})}):  # fmt: skip
        model = _load_text(json.dumps(candidate, allow_nan=True))
        if model is not None:
            _exercise(model, np.linspace(-200.0, 200.0, 7))


BASE_MODELS = {
    "pi": presets.paper_pi(),
    "mpi": presets.paper_mpi(),
    "preisach": presets.paper_preisach(),
    "preisach-table": Preisach.from_parameters(  # a small table: mutations reach every key
        table=presets.paper_preisach().everett_function(
            *np.meshgrid(np.linspace(0, 120, 4), np.linspace(0, 120, 4), indexing="ij")
        ),
        voltage_range=(0.0, 120.0),
        output_offset=-3.0,
    ),
}
BASE_MODELS["dynamics"] = LinearDynamics.from_parameters(
    sample_rate=20_000.0,
    resonance_hz=630.0,
    damping_ratio=0.08,
    creep_time_constants=[0.01, 0.1, 1.0],
    creep_weights=[0.01, 0.01, 0.01],
    delay_samples=1,
)
BASE_MODELS["hammerstein"] = HammersteinModel(presets.paper_mpi(), BASE_MODELS["dynamics"])
BASE_MODELS["hammerstein"].fit_report_ = {
    "rounds": 2,
    "tracking_estimates": {"1": {"alone_um": 0.1, "pair_um": 0.08}},
}
# a fit report too, as identify writes it: mutations reach the input range compensate reads
BASE_MODELS["pi"].fit_report_ = {"input_range_v": [0.0, 120.0], "rms_error_um": 0.1}
BASE_DOCUMENTS = [model_io.model_to_dict(m) for m in BASE_MODELS.values()]


@FUZZ
@given(
    which=st.sampled_from(range(len(BASE_DOCUMENTS))),
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


@pytest.mark.parametrize("name", list(BASE_MODELS))
def test_exercise_is_not_vacuous(name):
    """The fuzzing checks run on real models too: a valid document is loaded and exercised."""
    model = _load_text(json.dumps(model_io.model_to_dict(BASE_MODELS[name])))
    assert model is not None
    assert model.kind == name.split("-")[0]
    _exercise(model, np.linspace(-1e6, 1e6, 11))
