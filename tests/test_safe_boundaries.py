"""The boundary checks: model-file schema, magnitudes, conditioning, signals, no pickle."""

from __future__ import annotations

import ast
import copy
import json
from pathlib import Path

import numpy as np
import pytest

import hystcomp
from hystcomp import presets
from hystcomp._validation import MAX_MAGNITUDE, as_signal, as_vector, check_int, check_real
from hystcomp.errors import (
    DataFileError,
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
    ModelFileError,
    NotInvertibleError,
)
from hystcomp.identify.excitation import scaled_amplitudes, sinusoid_sequence, triangle_sequence
from hystcomp.io import models as model_io
from hystcomp.io.records import Record, parse_columns, read_table

SRC = Path(hystcomp.__file__).parent


def _mpi_doc():
    return model_io.model_to_dict(presets.paper_mpi())


def _edit(path, *keys, value=None, delete=False):
    def edit(doc):
        target = doc
        for key in path:
            target = target[key]
        for key in keys[:-1]:
            target = target[key]
        if delete:
            del target[keys[-1]]
        else:
            target[keys[-1]] = value
        return doc

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_edit((), "parameters", "weights", delete=True), r'no "weights" in its parameters'),
        (_edit(("parameters",), "gain", value=2.0), r'unknown parameter "gain" for a \'mpi\''),
        (_edit(("parameters",), "weights", 2, value=True), r'boolean true at parameters\["weights"\]\[2\]'),
        (_edit(("parameters",), "weights", 0, value="0.4"), r"text '0\.4' at parameters\[\"weights\"\]\[0\]"),
        (_edit(("parameters",), "weights", 0, value=[[1.0]]), r'nested too deep at parameters\["weights"\]\[0\]\[0\]'),
        (_edit(("parameters",), "input_offset", value={"v": 1}), r'an object at parameters\["input_offset"\]'),
        (_edit(("parameters",), "deadzone_weights", value=[1.0] * 3), r"'deadzone_weights' .*16 entries"),
        (_edit(("parameters",), "thresholds", 1, value=-1.0), r"'thresholds' .*strictly increasing"),
        (_edit(("parameters",), "voltage_range", value=[0, 120, 5]), r"'voltage_range' .*pair"),
        (_edit(("parameters",), "output_offset", value=1e300), r"'output_offset' .*at most 1e\+12"),
        (_edit((), "hyperparameters", value=[1]), r'"hyperparameters" that is not an object'),
        (_edit(("hyperparameters",), "n_operators", value={"a": 1}), r'invalid hyperparameter "n_operators"'),
        (_edit((), "fit_report", value="good"), r'"fit_report" that is not an object'),
        (_edit((), "kind", value=["mpi"]), r"model kind \['mpi'\]"),
        (_edit((), "version", value=1.0), r'no integer "version"'),
        (_edit((), "version", value=2), r"version 2, newer .*Upgrade hystcomp"),
        (_edit((), "parameters", value=[]), r'no "parameters" object'),
    ],
)  # fmt: skip
def test_model_documents_of_the_wrong_shape_name_the_key(tmp_path, edit, message):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(edit(_mpi_doc())))
    with pytest.raises(ModelFileError, match=message):
        hystcomp.load_model(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('{"a": NaN}', r"NaN is not a number a model file may hold"),
        ('{"a": -Infinity}', r"-Infinity is not a number"),
        ("[" * 50_000 + "]" * 50_000, r"nests arrays or objects too deeply"),
        ('{"a": ' + "1" * 5000 + "}", r"holds an integer of thousands of digits"),
        ("\x00\x01", r"not valid JSON"),
    ],
)
def test_model_files_that_are_not_plain_json(tmp_path, text, message):
    path = tmp_path / "m.json"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=message):
        hystcomp.load_model(path)


def test_model_file_size_and_kind_of_file(tmp_path, monkeypatch):
    path = tmp_path / "m.json"
    hystcomp.save_model(presets.paper_pi(), path)
    monkeypatch.setattr(model_io, "MAX_MODEL_FILE_BYTES", 100)
    with pytest.raises(ModelFileError, match=r"too large for a model file"):
        hystcomp.load_model(path)
    with pytest.raises(ModelFileError, match=r"not a regular file"):
        hystcomp.load_model("/dev/null")
    path.write_bytes(b"\x80\x81{")
    with pytest.raises(ModelFileError, match=r"not a text file"):
        hystcomp.load_model(path)
    path.write_bytes(b"\xff\xfe{")  # a UTF-16 byte-order mark
    with pytest.raises(ModelFileError, match=r"is UTF-16 text; save it as UTF-8\.$"):
        hystcomp.load_model(path)


def test_a_valid_document_still_round_trips_after_the_schema_checks():
    doc = _mpi_doc()
    model = model_io.model_from_dict(copy.deepcopy(doc))
    assert model_io.model_to_dict(model) == doc


def test_parameters_beyond_the_magnitude_bound_are_refused():
    with pytest.raises(
        InvalidParameterError, match=r"'weights' .*at most 1e\+12 in size\. Entry 1"
    ):
        hystcomp.PrandtlIshlinskii.from_parameters(thresholds=[0, 1], weights=[1.0, 2e12])
    for bad in (10**400, float("inf"), 2e12):
        with pytest.raises(InvalidParameterError, match="magnitude at most"):
            check_real(bad, "input_offset", "test")
    with pytest.raises(InvalidTypeError, match="1-D array of real numbers"):
        as_vector([1, 10**400], "weights", "test")
    with pytest.raises(InvalidParameterError, match=r"int <= 10"):
        check_int(11, "n", "test", maximum=10)


@pytest.mark.parametrize("bad", [["1.0", "2.0"], [True, False], [1 + 2j], np.array(["a"])])
def test_text_booleans_and_complex_are_not_numbers(bad):
    with pytest.raises(InvalidTypeError):
        as_vector(bad, "weights", "test")
    with pytest.raises(InvalidTypeError):
        as_signal(bad, "v")


def test_signals_reach_the_kernels_as_one_array_type():
    """Read-only, strided or integer samples become a writable C-contiguous float64 array,
    so that a kernel is compiled once whatever array the caller holds (a Record's samples
    are read-only; each array type would be a compilation of its own)."""
    frozen = np.linspace(0.0, 100.0, 9)
    frozen.setflags(write=False)
    for given in (frozen, np.linspace(0.0, 100.0, 18)[::2], np.arange(9), [0.0, 1.0]):
        u = as_signal(given, "v")
        assert u.dtype == np.float64
        assert u.flags.c_contiguous
        assert u.flags.writeable
    assert not frozen.flags.writeable  # the caller's array is left as it was
    plain = np.linspace(0.0, 100.0, 9)
    assert as_signal(plain, "v") is plain  # no copy when none is needed

    from hystcomp._kernels.chain import chain_run

    model = presets.paper_pi()
    model.simulate(plain)
    compiled = len(chain_run.signatures)
    record = Record(np.arange(9) / 20_000.0, plain, plain)
    np.testing.assert_array_equal(model.simulate(record.v), model.simulate(plain))
    assert len(chain_run.signatures) == compiled


def test_signals_beyond_the_magnitude_bound_name_the_sample():
    model = presets.paper_pi()
    with pytest.raises(InvalidSignalError, match=r"Sample 2 is 1e\+13; check the units"):
        model.simulate([0.0, 1.0, 1e13])
    assert np.all(np.isfinite(model.simulate([MAX_MAGNITUDE, -MAX_MAGNITUDE])))


def test_inverse_refuses_partial_sums_too_close_to_zero_naming_the_index():
    model = hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=[0, 1, 2], weights=[1e-10, 1e-10, -1.9999999999999999e-10]
    )
    with pytest.raises(NotInvertibleError, match=r"in floating point.*index 2") as err:
        model.inverse()
    assert err.value.index == 2
    tiny = hystcomp.PrandtlIshlinskii.from_parameters(thresholds=[0], weights=[1e-30])
    with pytest.raises(NotInvertibleError, match=r"the first weight w_0 = 1e-30 .*index 0"):
        tiny.inverse()
    second = hystcomp.PrandtlIshlinskii.from_parameters(thresholds=[0, 1], weights=[1.0, -1.0])
    with pytest.raises(NotInvertibleError, match=r"weights w_0 \+ w_1 = 0 .*index 1"):
        second.inverse()


def test_the_most_extreme_accepted_inverse_stays_finite_and_in_range():
    """Weights at the bounds: the largest inverse weights and the largest inputs allowed."""
    model = hystcomp.ModifiedPrandtlIshlinskii.from_parameters(
        thresholds=[0.0, 1e12],
        weights=[1e12, -1e12 + 2e-12 * 1e12],
        deadzone_thresholds=[0.0, 1e12],
        deadzone_weights=[1e-12, 1e12],
        input_offset=-1e12,
        output_offset=1e12,
    )
    x = np.array([MAX_MAGNITUDE, -MAX_MAGNITUDE, 0.0, 1.0, MAX_MAGNITUDE])
    assert np.all(np.isfinite(model.simulate(x)))
    v = model.inverse().simulate(x)
    assert np.all((v >= 0.0) & (v <= 120.0))


def test_excitation_signals_validate_their_arguments():
    with pytest.raises(InvalidParameterError, match=r"2 samples per period .* at least 4"):
        triangle_sequence(sample_rate=2.0)
    with pytest.raises(InvalidParameterError, match=r"more than 1e\+08"):
        sinusoid_sequence(sample_rate=1e9)
    with pytest.raises(InvalidParameterError, match=r"'amplitudes' .* >= 0 V"):
        triangle_sequence([10.0, -5.0])
    with pytest.raises(InvalidParameterError, match=r"'v_min'"):
        triangle_sequence(v_min=float("nan"))
    with pytest.raises(InvalidParameterError, match=r"'paper_range'"):
        scaled_amplitudes([1.0], paper_range=(1.0, 1.0))


def test_record_validates_its_columns():
    with pytest.raises(InvalidSignalError, match=r"one sample each per instant"):
        Record(np.arange(3.0), np.zeros(3), np.zeros(2))
    with pytest.raises(InvalidSignalError, match=r"strictly increasing"):
        Record(np.array([0.0, 1.0, 1.0]), np.zeros(3), np.zeros(3))
    with pytest.raises(InvalidSignalError, match=r"Record 'v'.*finite"):
        Record(np.arange(2.0), np.array([0.0, np.nan]), np.zeros(2))
    v = np.array([0.0, 1.0])
    rec = Record(np.arange(2.0), v, np.zeros(2))
    v[0] = 5.0
    assert rec.v[0] == 0.0
    assert not rec.v.flags.writeable


def test_read_table_checks_its_own_arguments(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("t,v,x\n0,0,0\n1,1,1\n")
    with pytest.raises(
        InvalidParameterError, match=r"'keys' and 'optional' parameters of read_table"
    ):
        read_table(path, ("y",))
    with pytest.raises(InvalidParameterError, match=r"'min_samples'"):
        read_table(path, min_samples=0)
    with pytest.raises(InvalidTypeError, match=r"'path' parameter of read_table"):
        read_table(3.5)
    np.savez(tmp_path / "c.npz", t=np.arange(2.0), v=np.ones(2) * 1j, x=np.ones(2))
    with pytest.raises(DataFileError, match=r"'v'.*holds complex numbers"):
        read_table(tmp_path / "c.npz")


def test_column_numbers_are_ascii_digits():
    assert parse_columns("v=²") == {"v": "²"}  # a name, not the number 2
    assert parse_columns("v=12") == {"v": 12}


def test_no_pickle_anywhere_in_the_package():
    """Model and data files are data: nothing in the package may unpickle."""
    forbidden_modules = {"pickle", "cPickle", "dill", "joblib", "shelve", "marshal"}
    # joblib's Parallel sends tasks between this program's own processes (or a dask
    # cluster's workers), never to or from a file: those names alone are allowed from it
    parallel_only = {"Parallel", "delayed", "parallel_config"}
    for path in SRC.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module == "joblib":
                assert {a.name for a in node.names} <= parallel_only, path
                continue
            if isinstance(node, ast.Import | ast.ImportFrom):
                names = [a.name for a in node.names] + [getattr(node, "module", None) or ""]
                assert not forbidden_modules & {n.split(".")[0] for n in names}, path
            if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "load":
                owner = getattr(node.func.value, "id", "")
                if owner in ("np", "numpy"):
                    keywords = {k.arg: k.value for k in node.keywords}
                    flag = keywords.get("allow_pickle")
                    assert isinstance(flag, ast.Constant), path
                    assert flag.value is False, path
            if isinstance(node, ast.keyword) and node.arg == "allow_pickle":
                assert isinstance(node.value, ast.Constant), path
                assert node.value.value is False, path


GARBAGE = [None, "abc", [], [[1.0, 2.0]], float("nan"), -1, 10**400, object(), [1.0, np.nan]]
PUBLIC = {
    "simulate": lambda a: presets.paper_pi().simulate(a),
    "inverse simulate": lambda a: presets.paper_mpi().inverse().simulate(a),
    "inverse options": lambda a: presets.paper_mpi().inverse(slew_rate=a, sample_rate=a),
    "inverse voltage_range": lambda a: presets.paper_mpi().inverse(voltage_range=a),
    "fit": lambda a: hystcomp.PrandtlIshlinskii(n_operators=2).fit(a, a),
    "fit hyperparameters": lambda a: hystcomp.ModifiedPrandtlIshlinskii(
        n_operators=a, n_deadzones=a, transient=a, margin=a
    ).fit(np.r_[0:10, 10:0:-1.0], np.r_[0:10, 10:0:-1.0]),
    "from_parameters": lambda a: hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=a, weights=a
    ),
    "from_dict": lambda a: hystcomp.PrandtlIshlinskii.from_dict(a),
    "model_from_dict": lambda a: model_io.model_from_dict(a),
    "load_model": lambda a: hystcomp.load_model(a),
    "save_model": lambda a: hystcomp.save_model(a, a),
    "read_table": lambda a: read_table(a),
    "read_table columns": lambda a: read_table(SRC / "py.typed", columns=a, sample_rate=a),
    "write_table": lambda a: hystcomp.io.records.write_table(a, {"t": a}),
    "format_csv": lambda a: hystcomp.io.records.format_csv(a),
    "rate_of": lambda a: hystcomp.io.records.rate_of(a),
    "Record": lambda a: Record(a, a, a),
    "parse_columns": lambda a: parse_columns(a),
    "triangle_sequence": lambda a: triangle_sequence(a, sample_rate=a, frequency=a),
    "fit_pi": lambda a: hystcomp.identify.pi.fit_pi(a, a),
    "paper_thresholds": lambda a: hystcomp.identify.pi.paper_thresholds(a, a),
    "error_report": lambda a: hystcomp.identify.scoring.error_report(a, a),
    "straight_line": lambda a: hystcomp.identify.scoring.straight_line(a, a),
    "absorb_bias": lambda a: hystcomp.identify.mpi.absorb_bias(a, a, a, a),
}


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_public_functions_refuse_garbage_with_package_errors(name):
    """Each value is accepted or refused with a hystcomp error, never another exception."""
    refused = 0
    for value in GARBAGE:
        try:
            PUBLIC[name](value)
        except hystcomp.errors.HystcompError:
            refused += 1
    assert refused >= 4
