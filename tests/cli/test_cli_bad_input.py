"""Bad input through the real command (a process): exit 2, one line, no harm to any file.

Each case runs the program as ``python -m hystcomp ...`` does, with this checkout's
sources, in a folder where its output file already exists. The table is run once, in
parallel, by a module fixture: each case in a process of its own, forked from one parent
that has imported hystcomp and its dependencies once (:data:`FORK_SERVER`; a fresh
interpreter per case spent most of its second importing them), and a test holds a few
cases run that way to the same cases run as fresh ``python -m hystcomp`` processes. Each
case then checks: exit status 2, exactly one line on standard error naming the problem (a
regex), no traceback, and the existing output file unchanged byte for byte and in its
modification time, with no temporary file left behind.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import scipy.io

import hystcomp
from hystcomp import presets
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import write_table

SRC = Path(hystcomp.__file__).parents[1]
PRECIOUS = b"precious: an earlier result that a failing command must not touch\n"
MTIME_NS = 1_000_000_000 * 1_000_000_000  # 2001-09-09, set on every existing output
MODEL = '{"format": "hystcomp-model", "version": %s, "kind": "pi", "parameters": %s}'

# (case id, arguments; {out} and {fig} are this case's existing outputs, message regex)
CASES = [
    ("missing data file", "identify nowhere.csv --model pi -o {out}.json", r"'nowhere\.csv' does not exist"),
    ("binary data file", "identify binary.csv --model pi -o {out}.json", r"'binary\.csv' is not text"),
    ("empty data file", "identify empty.csv --model pi -o {out}.json", r"'empty\.csv' is empty"),
    ("missing column", "identify no_x.csv --model pi -o {out}.json", r"no column 'x' .*--columns x=NAME"),
    ("NaN in the input", "identify nan.csv --model pi -o {out}.json", r"'v' .*non-finite value \(nan\) in data row 2"),
    ("time not increasing", "identify backwards.csv --model pi -o {out}.json", r"'t' .*not strictly increasing: data row 3"),
    ("too few samples", "identify one.csv --model pi -o {out}.json", r"has 1 sample; at least 2"),
    ("constant input", "identify flat.csv --model pi -o {out}.json", r"'v' .* is constant \(5\.0 V\).*sweeps"),
    ("operators <= 0", "identify rec.csv --model pi --operators 0 -o {out}.json", r"'--operators': must be between 1 and 256"),
    ("operators > 256", "identify rec.csv --model mpi --deadzones 1000 -o {out}.json", r"'--deadzones': must be between 1 and 256 .*cube"),
    ("unknown model kind", "identify rec.csv --model bogus -o {out}.json", r"'--model': 'bogus' is not one of"),
    ("holdout outside (0,1)", "identify rec.csv --model pi --holdout 1.5 -o {out}.json", r"'--holdout': must be between 0 and 1"),
    ("bad --columns", "identify rec.csv --model pi --columns v=1,,x=2 -o {out}.json", r"'--columns'.*must look like v=1,x=5"),
    ("bad sample rate", "identify rec.csv --model pi --fs 0 -o {out}.json", r"'--fs': must be a number > 0 \(Hz\)"),
    ("fails after the fit started", "identify rec.csv --model pi --transient 1e9 --plot {fig}.png -o {out}.json", r"only 0 of 801 samples remain"),
    ("missing output folder", "identify rec.csv --model pi -o nowhere/m.json", r"folder 'nowhere' does not exist"),
    ("output is a folder", "simulate model.json rec.csv -o a_folder", r"'a_folder': it is a folder"),
    ("output is the input", "identify rec.csv --model pi -o rec.csv", r"'rec\.csv': it is the input file 'rec\.csv'"),
    ("model is not JSON", "simulate rec.csv rec.csv -o {out}.csv", r"'rec\.csv' is not valid JSON"),
    ("model is a JSON list", "simulate list.json rec.csv -o {out}.csv", r"'list\.json' is not a hystcomp model file"),
    ("model holds NaN", "simulate nan.json rec.csv -o {out}.csv", r"'nan\.json' .*NaN is not a number a model file may hold"),
    ("newer model version", "simulate v9.json rec.csv -o {out}.csv", r"format version 9, newer .*Upgrade hystcomp"),
    ("mismatched lengths", "simulate lengths.json rec.csv -o {out}.csv", r"'weights' parameter .* must have 3 entries"),
    ("wrong JSON type", "simulate text.json rec.csv -o {out}.csv", r"the text 'x' at parameters\[\"weights\"\]\[1\]"),
    ("not invertible", "compensate not_invertible.json ref.csv -o {out}.csv", r"not invertible: .*\(index 3\)"),
    ("NaN in the reference", "compensate model.json ref_nan.csv -o {out}.csv", r"'x' .*non-finite value \(nan\) in data row 2"),
    ("negative slew rate", "compensate model.json ref.csv --slew-rate -1 -o {out}.csv", r"'--slew-rate': must be a number > 0 \(V/s\)"),
    ("widened voltage range", "compensate model.json ref.csv --voltage-range 0 150 -o {out}.csv", r"may only narrow the model's voltage range 0 \.\. 120 V"),
    ("excite: bad sample rate", "excite pi --fs -5 -o {out}.csv", r"'--fs': must be a number > 0"),
    ("dynamics as the model", "simulate dyn.json rec.csv -o {out}.csv", r"'dyn\.json' holds linear dynamics, not a hysteresis model; simulate runs"),
    ("export-c negative slew rate", "export-c model.json -o {out}_c --slew-rate -1", r"'--slew-rate': must be a number > 0 \(V/s\)"),
    ("degree with grid", "identify rec.csv --model preisach --degree 3 --grid 10 -o {out}.json", r"--grid and --degree exclude each other"),
    ("empty output name", "identify rec.csv --model pi -o ''", r"its path is empty\. Give a file name"),
    ("output folder is a file", "identify rec.csv --model pi -o rec.csv/{out}.json", r"the folder 'rec\.csv' is a file, not a folder"),
    ("file name too long", "excite mpi -o %s.csv" % ("a" * 300), r"cannot use 'a+': File name too long\. Check the path"),
    ("holdout leaves too few", "identify rec.csv --model pi --holdout 0.99 -o {out}.json", r"fewer than the \d+ needed.*'holdout' .*0\.99, leaves the first 8 of 801 samples .*smaller fraction"),
    ("regularization too large", "identify rec.csv --model mpi --regularization 1e308 -o {out}.json", r"'--regularization': must be 'auto' or a number from 0 to 1e\+12; got '1e308'"),
    ("--columns not read", "compensate model.json ref.csv --columns v=2 -o {out}.csv", r"'--columns': v=2 names a column of voltage, which this command does not read .* --columns x=2"),
    ("excite: period too long", "excite mpi --frequency 1e-300 -o {out}.csv", r"one period at 1e-300 Hz is 2e\+304 samples at 20000 Hz, more than 1e\+08\. Raise the frequency"),
    ("excite dynamics: rate too high", "excite dynamics --fs 1e12 -o {out}.csv", r"'--fs': makes the 9\.16 s signal 9\.16e\+12 samples long, .* use at most"),
    ("export-c: huge --fs", "export-c model.json -o {out}_c --fs 1e308", r"'--fs': must be a finite number of size at most 1e\+12"),
    ("export-c onto a file", "export-c model.json -o rec.csv", r"'rec\.csv': it exists and is not a folder"),
    ("UTF-16 data file", "identify u16.csv --model pi -o {out}.json", r"'u16\.csv' is UTF-16 text; save it as UTF-8\.$"),
    ("UTF-16 model file", "simulate u16.json rec.csv -o {out}.csv", r"'u16\.json' is UTF-16 text; save it as UTF-8\.$"),
    ("integer of 5000 digits", "simulate digits.json rec.csv -o {out}.csv", r"'digits\.json' holds an integer of thousands of digits"),
    ("preisach transient too long", "identify rec.csv --model preisach --transient 1e9 -o {out}.json", r"identify_record \(preisach\): only 0 of 801 samples remain .*\(--transient\)"),
    ("hysteresis record as dynamics", "identify rec.csv --model dynamics -o {out}.json", r"does not have the layout of hystcomp excite dynamics: found a hold of"),
    ("hyperparameter as text", "simulate quoted.json rec.csv -o {out}.csv", r"'n_operators' .* is the text '16', not a number, .* set 'n_operators' to 16 \(no quotes\)"),
    ("initial memory for pi", "identify rec.csv --model pi --initial-memory descended -o {out}.json", r"--initial-memory does not apply to --model pi"),
    ("preisach range inside the record", "identify rec.csv --model preisach --voltage-range 10 100 -o {out}.json", r"'--voltage-range': must contain the record's input, .* narrow the compensator's clamp instead \(--voltage-range of compensate"),
    ("dynamics record with a gap", "identify gap.csv --model dynamics -o {out}.json", r"record gap\.csv is not evenly sampled: 1 step differs .* from t = 0\.095 to 0\.125 s \(data row 21\)\. .*resample"),
    ("reference with a gap, dynamics", "compensate model.json ref_gap.csv --dynamics dyn.json -o {out}.csv", r"of the reference is not evenly sampled: 2 steps differ"),
]  # fmt: skip

EXTENDED = [
    ("device as data", "identify /dev/zero --model pi -o {out}.json", r"not a regular file"),
    ("folder as data", "identify a_folder --model pi -o {out}.json", r"'a_folder' is a folder"),
    (".npy as .npz", "identify array.npz --model pi -o {out}.json", r"single \.npy array"),
    ("pickled .npz", "identify objects.npz --model pi -o {out}.json", r"allow_pickle=False"),
    ("complex column", "identify complex.npz --model pi -o {out}.json", r"holds complex numbers"),
    ("MAT that crashes scipy", "identify crash.mat --model pi -o {out}.json", r"not a readable MATLAB \.mat file"),
    ("huge value", "identify huge.csv --model pi -o {out}.json", r"value 1e\+13 in data row 2, beyond 1e\+12"),
    ("absurd time", "identify tiny_t.csv --model pi -o {out}.json", r"no usable sample rate"),
    ("--fs and t disagree", "identify rec.csv --model pi --fs 100 -o {out}.json", r"says 200 Hz .* 100 Hz"),
    ("operators too many", "identify rec.csv --model pi --operators 5000 -o {out}.json", r"between 1 and 256"),
    ("operators not a number", "identify rec.csv --model pi --operators abc -o {out}.json", r"'abc' is not a valid integer"),
    ("holdout NaN", "identify rec.csv --model pi --holdout nan -o {out}.json", r"between 0 and 1"),
    ("transient inf", "identify rec.csv --model pi --transient inf -o {out}.json", r"finite number"),
    ("voltage range NaN", "identify rec.csv --model pi --voltage-range nan 5 -o {out}.json", r"finite number"),
    ("figure folder missing", "identify rec.csv --model pi --plot nowhere/f.png -o {out}.json", r"folder 'nowhere' does not exist"),
    ("deep JSON", "simulate deep.json rec.csv -o {out}.csv", r"nests arrays or objects too deeply"),
    ("enormous integer", "simulate bigint.json rec.csv -o {out}.csv", r"'weights' .*(finite|real numbers)"),
    ("kind is a list", "simulate kind_list.json rec.csv -o {out}.csv", r"model kind \['pi'\]"),
    ("unknown parameter", "simulate extra.json rec.csv -o {out}.csv", r"unknown parameter \"gain\""),
    ("boolean weight", "simulate boolean.json rec.csv -o {out}.csv", r"the boolean true at parameters\[\"weights\"\]\[0\]"),
    ("ill-conditioned inverse", "compensate tiny_sum.json ref.csv -o {out}.csv", r"not invertible in floating point.*index 1"),
    ("output is the model", "simulate model.json rec.csv -o model.json", r"it is the input file 'model\.json'"),
    ("unknown output format", "simulate model.json rec.csv -o {out}.xlsx", r"unknown format '\.xlsx'"),
    ("reversed voltage range", "compensate model.json ref.csv --voltage-range 50 10 -o {out}.csv", r"LO < HI"),
    ("slew rate inf", "compensate model.json ref.csv --slew-rate inf -o {out}.csv", r"finite number"),
    ("reference = output", "compensate model.json ref.csv -o ref.csv", r"it is the input file 'ref\.csv'"),
    ("excite: too many samples", "excite pi --fs 1e11 -o {out}.csv", r"more than 1e\+08"),
    ("excite: too few per period", "excite pi --fs 2 -o {out}.csv", r"at least 4 are needed"),
    ("excite: reversed range", "excite mpi --voltage-range 10 5 -o {out}.csv", r"LO < HI"),
    ("unknown command", "nosuchcommand", r"No such command 'nosuchcommand'"),
]  # fmt: skip


def _make_files(folder: Path) -> None:
    t, v = triangle_sequence(sample_rate=200.0)
    write_table(folder / "rec.csv", {"t": t, "v": v, "x": presets.paper_mpi().simulate(v)})
    hystcomp.save_model(presets.paper_mpi(), folder / "model.json")
    dyn = hystcomp.LinearDynamics.from_parameters(
        sample_rate=200.0, resonance_hz=40.0, damping_ratio=0.1,
        creep_time_constants=[0.1], creep_weights=[0.01],
    )  # fmt: skip
    hystcomp.save_model(dyn, folder / "dyn.json")
    t_ref = np.arange(500) / 1000.0
    write_table(folder / "ref.csv", {"t": t_ref, "x": 10.0 + 5.0 * np.sin(2 * np.pi * t_ref)})
    texts = {
        "binary.csv": bytes(range(256)).decode("latin-1"),
        "empty.csv": "",
        "no_x.csv": "t,v\n0,0\n1,1\n",
        "nan.csv": "t,v,x\n0,0,0\n1,nan,1\n2,1,2\n",
        "backwards.csv": "t,v,x\n0,0,0\n1,1,1\n0.5,2,2\n",
        "one.csv": "t,v,x\n0,0,0\n",
        "flat.csv": "t,v,x\n" + "".join(f"{i},5,{i}\n" for i in range(50)),
        "ref_nan.csv": "t,x\n0,1\n0.001,nan\n0.002,3\n",
        "gap.csv": "t,v,x\n"
        + "".join(f"{0.005 * (i + 5 * (i > 19))},{i % 7},{i % 5}\n" for i in range(60)),
        "ref_gap.csv": "t,x\n"
        + "".join(f"{0.005 * (i + (i > 9) + (i > 30))},1\n" for i in range(60)),
        "huge.csv": "t,v,x\n0,0,0\n1,1e13,1\n",
        "tiny_t.csv": "t,v,x\n0,0,0\n5e-324,1,1\n1e-323,2,2\n",
        "list.json": "[1, 2, 3]",
        "nan.json": MODEL % (1, '{"thresholds": [0, 1], "weights": [NaN, 1]}'),
        "v9.json": MODEL % (9, "{}"),
        "lengths.json": MODEL % (1, '{"thresholds": [0, 1, 2], "weights": [1, 1]}'),
        "text.json": MODEL % (1, '{"thresholds": [0, 1], "weights": [1, "x"]}'),
        "deep.json": "[" * 100_000 + "]" * 100_000,
        "bigint.json": MODEL % (1, '{"thresholds": [0, 1], "weights": [%s, 1]}' % ("9" * 400)),
        "kind_list.json": MODEL.replace('"pi"', '["pi"]') % (1, "{}"),
        "extra.json": MODEL % (1, '{"thresholds": [0], "weights": [1], "gain": 2}'),
        "boolean.json": MODEL % (1, '{"thresholds": [0], "weights": [true]}'),
        "tiny_sum.json": MODEL
        % (1, '{"thresholds": [0, 1], "weights": [1e-10, -9.99999999999999e-11]}'),
    }
    for name, text in texts.items():
        (folder / name).write_text(text, encoding="latin-1" if name == "binary.csv" else "utf-8")
    doc = json.loads((folder / "model.json").read_text())
    doc["kind"] = "pi"
    doc["parameters"] = hystcomp.io.model_to_dict(presets.paper_pi())["parameters"]
    doc["parameters"]["weights"][3] = -1.0  # w_0 + ... + w_3 < 0
    (folder / "not_invertible.json").write_text(json.dumps(doc))
    doc = json.loads((folder / "model.json").read_text())
    doc["hyperparameters"]["n_operators"] = "16"
    (folder / "quoted.json").write_text(json.dumps(doc))
    (folder / "a_folder").mkdir()
    np.save(folder / "array.npy", np.arange(3.0))
    (folder / "array.npy").rename(folder / "array.npz")
    np.savez(folder / "objects.npz", t=np.arange(3.0), v=np.array([1, "a"], dtype=object))
    np.savez(folder / "complex.npz", t=np.arange(3.0), v=np.arange(3.0) + 1j, x=np.arange(3.0))
    (folder / "crash.mat").write_bytes(crashing_mat_bytes())
    (folder / "u16.csv").write_bytes("t,v,x\n0,0,0\n1,1,1\n".encode("utf-16"))
    (folder / "u16.json").write_bytes((folder / "model.json").read_text().encode("utf-16"))
    (folder / "digits.json").write_text(MODEL % (1, '{"thresholds": [%s]}' % ("9" * 5000)))


def crashing_mat_bytes() -> bytes:
    """A MAT file with an invalid data type code (242) in a numeric element.

    scipy's MAT reader (1.17) looks the code up in a table without a range check and
    crashes the interpreter (a segmentation fault) on it.
    """
    import io

    buffer = io.BytesIO()
    scipy.io.savemat(buffer, {"v": np.array([[1.0]])})
    data = bytearray(buffer.getvalue())
    tag = data.index(np.array([9, 8], dtype="<u4").tobytes(), 128)  # miDOUBLE, 8 bytes
    data[tag : tag + 4] = np.array([242], dtype="<u4").tobytes()
    return bytes(data)


def _prepare(folder: Path, cases) -> dict:
    """The argument lists of ``cases``, with their outputs already existing (precious)."""
    jobs = {}
    for i, (name, args, _) in enumerate(cases):
        argv = shlex.split(args.format(out=f"out{i}", fig=f"fig{i}"))
        existing = [folder / a for a in argv if a.startswith(("out", "fig"))]
        for path in existing:
            path.write_bytes(PRECIOUS)
            os.utime(path, ns=(MTIME_NS, MTIME_NS))
        jobs[name] = (argv, existing)
    return jobs


def _env() -> dict:
    return {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
    }


def _run_fresh(folder: Path, jobs: dict) -> dict:
    """Run every job as a fresh ``python -m hystcomp`` in ``folder``, in parallel."""

    def run(item):
        name, (argv, existing) = item
        result = subprocess.run(
            [sys.executable, "-m", "hystcomp", *argv],
            cwd=folder,
            env=_env(),
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
        return name, (result, existing)

    with ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 2)) as pool:
        return dict(pool.map(run, jobs.items()))


#: The parent of the forked cases: it imports every module of hystcomp (and so numpy,
#: pandas, scipy, numba and matplotlib), then, at most ``workers`` at a time, forks a child
#: per job that runs ``hystcomp/__main__.py`` as ``python -m hystcomp`` does, in the job's
#: folder, with its own arguments, standard input from /dev/null and its standard output
#: and error into files of ``streams``. The program ends its process itself
#: (:func:`hystcomp.cli.run`); the parent writes each child's exit status as JSON.
FORK_SERVER = r"""
import json, os, pkgutil, runpy, sys, traceback
import hystcomp

for info in pkgutil.walk_packages(hystcomp.__path__, "hystcomp."):
    if not info.name.endswith("__main__"):
        __import__(info.name)
folder, streams, workers, jobs = json.load(sys.stdin)
sys.stdout.flush()
sys.stderr.flush()


def child(i, argv):
    os.chdir(folder)
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    for fd, what in ((1, "out"), (2, "err")):
        path = os.path.join(streams, f"{i}.{what}")
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), fd)
    sys.argv = ["-m", *argv]
    code = 1
    try:
        runpy.run_module("hystcomp", run_name="__main__", alter_sys=True)
        code = 0
    except SystemExit as exc:  # as the interpreter ends on it
        code = exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 1
        if not isinstance(exc.code, int | None):
            print(exc.code, file=sys.stderr)
    except BaseException:
        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


running, status = {}, {}
for i, argv in enumerate(jobs):
    if len(running) == workers:
        pid, wait = os.wait()
        status[running.pop(pid)] = os.waitstatus_to_exitcode(wait)
    pid = os.fork()
    if pid == 0:
        child(i, argv)
    running[pid] = i
while running:
    pid, wait = os.wait()
    status[running.pop(pid)] = os.waitstatus_to_exitcode(wait)
print(json.dumps([status[i] for i in range(len(jobs))]))
"""


def _run(folder: Path, jobs: dict, streams: Path) -> dict:
    """Run every job in ``folder`` in a process forked from :data:`FORK_SERVER`."""
    names = list(jobs)
    argvs = [jobs[name][0] for name in names]
    workers = max(2, os.cpu_count() or 2)
    done = subprocess.run(
        [sys.executable, "-c", FORK_SERVER],
        input=json.dumps([str(folder), str(streams), workers, argvs]),
        env=_env(),
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    codes = json.loads(done.stdout.splitlines()[-1])
    results = {}
    for i, (name, code) in enumerate(zip(names, codes, strict=True)):
        out, err = ((streams / f"{i}.{what}").read_text() for what in ("out", "err"))
        result = subprocess.CompletedProcess(
            ["python", "-m", "hystcomp", *argvs[i]], code, out, err
        )
        results[name] = (result, jobs[name][1])
    return results


def _snapshot(folder: Path) -> dict:
    """Every file of ``folder`` (recursively): its bytes and modification time."""
    return {
        str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns)
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def _check(result, existing, pattern):
    assert result.returncode == 2, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("hystcomp: error: ")
    assert re.search(pattern, lines[0]), lines[0]
    for path in existing:  # the existing outputs: byte for byte, and not even touched
        assert path.read_bytes() == PRECIOUS
        assert path.stat().st_mtime_ns == MTIME_NS


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad_input")
    _make_files(folder)
    jobs = _prepare(folder, CASES)
    before = _snapshot(folder)
    return before, _snapshot, folder, _run(folder, jobs, tmp_path_factory.mktemp("streams"))


@pytest.mark.parametrize(
    ("name", "pattern"), [(c[0], c[2]) for c in CASES], ids=[c[0] for c in CASES]
)
def test_bad_input_exits_2_in_one_line_and_harms_nothing(table, name, pattern):
    *_, results = table
    _check(*results[name], pattern)


def test_the_failing_commands_left_every_file_as_it_was(table):
    before, snapshot, folder, _ = table
    assert snapshot(folder) == before  # no file changed, none created (no temporary left)


#: Cases run both ways: an error of the record reader, of the model file, and of an option.
PARITY = ("missing data file", "NaN in the input", "model holds NaN", "bad sample rate")


def test_a_forked_case_is_the_case_run_by_a_fresh_interpreter(table, tmp_path):
    *_, forked = table
    _make_files(tmp_path)
    cases = [case for case in CASES if case[0] in PARITY]
    fresh = _run_fresh(tmp_path, _prepare(tmp_path, cases))
    assert set(fresh) == set(PARITY)
    for name, _, pattern in cases:
        _check(*fresh[name], pattern)
        a, b = forked[name][0], fresh[name][0]
        assert (a.returncode, a.stdout, a.stderr) == (b.returncode, b.stdout, b.stderr), name


@pytest.mark.slow
def test_extended_bad_input_table(tmp_path):
    _make_files(tmp_path)
    jobs = _prepare(tmp_path, EXTENDED)
    before = _snapshot(tmp_path)
    results = _run_fresh(tmp_path, jobs)  # fresh: one case crashes scipy's reader
    failures = []
    for name, _, pattern in EXTENDED:
        try:
            _check(*results[name], pattern)
        except AssertionError as exc:
            failures.append(f"{name}: {exc}")
    assert not failures, "\n".join(failures)
    assert _snapshot(tmp_path) == before


def test_a_mat_file_that_crashes_scipy_is_a_clean_error(tmp_path):
    """The reader runs scipy in a child process, so even a crash of scipy is a clean error."""
    path = tmp_path / "crash.mat"
    path.write_bytes(crashing_mat_bytes())
    with pytest.raises(hystcomp.errors.DataFileError, match=r"not a readable MATLAB .*corrupt"):
        hystcomp.io.records.read_table(path)
    code = f"import scipy.io; scipy.io.loadmat({str(path)!r})"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, check=False)
    if result.returncode >= 0:
        pytest.skip("this scipy no longer crashes on the file (it raises or reads it)")


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs Linux's /dev/full")
def test_a_signal_to_a_full_standard_output_is_a_clean_error(tmp_path):
    with open("/dev/full", "w") as full:
        result = subprocess.run(
            [sys.executable, "-m", "hystcomp", "excite", "mpi"],
            stdout=full, stderr=subprocess.PIPE, text=True, env=_env(), cwd=tmp_path, check=False,
        )  # fmt: skip
    assert result.returncode == 2
    expected = (
        "hystcomp: error: Cannot write the signal to standard output: No space left on "
        "device. Give a file with -o, or check where standard output goes."
    )
    assert result.stderr.splitlines() == [expected]
