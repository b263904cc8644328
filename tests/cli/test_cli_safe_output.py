"""The commanded voltage is always safe, and a failing command writes nothing.

In-process (click's runner) for speed; the subprocess table of bad inputs is in
``test_cli_bad_input.py``.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import HystcompError, InvalidParameterError, OutputPathError
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.atomic import atomic_paths
from hystcomp.io.records import read_table, write_table
from tests.conftest import invertible_weights

ABSURD = np.array([1e6, -1e6, 0.0, 1e6, -5.0, 30.0, -1e6, 1e6, 12.0, -1e3])


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def bipolar_pi(rng):
    """A PI model of a ±150 V stage with a sensor offset (not the paper's 0..120 V)."""
    r = np.arange(8) * 300.0 / 8
    return hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=r,
        weights=invertible_weights(rng, 8, scale=0.2),
        voltage_range=(-150.0, 150.0),
        input_offset=-150.0,
        output_offset=-40.0,
    )


@pytest.mark.parametrize("kind", ["mpi", "bipolar"])
def test_compensate_output_stays_in_range_for_absurd_references(tmp_path, rng, kind):
    model = presets.paper_mpi() if kind == "mpi" else bipolar_pi(rng)
    hystcomp.save_model(model, tmp_path / "m.json")
    x_ref = np.concatenate([ABSURD, 1e6 * rng.standard_normal(500)])
    write_table(tmp_path / "ref.csv", {"t": np.arange(x_ref.size) / 1e3, "x": x_ref})
    result = run("compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v.csv")
    assert result.exit_code == 0, result.output
    v = read_table(tmp_path / "v.csv", ("v",))["v"]
    lo, hi = model.voltage_range_
    assert np.all(np.isfinite(v))
    assert lo <= v.min()
    assert v.max() <= hi
    assert v.min() == lo
    assert v.max() == hi


def test_narrowed_voltage_range_is_the_clamp(tmp_path):
    hystcomp.save_model(presets.paper_mpi(), tmp_path / "m.json")
    write_table(tmp_path / "ref.csv", {"t": np.arange(ABSURD.size) / 1e3, "x": ABSURD})
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v.csv"]
    result = run(*args, "--voltage-range", 10, 100)
    assert result.exit_code == 0, result.output
    assert "clamped to 10 .. 100 V" in result.output
    v = read_table(tmp_path / "v.csv", ("v",))["v"]
    assert (v.min(), v.max()) == (10.0, 100.0)


def test_narrowing_in_python_and_refusing_to_widen():
    model = presets.paper_pi()
    comp = model.inverse(voltage_range=(20.0, 60.0))
    assert comp.voltage_range == (20.0, 60.0)
    stepper = comp.stepper()
    assert [stepper.step(x) for x in (-1e6, 1e6, 5.0)][:2] == [20.0, 60.0]
    for wide in ((-1.0, 60.0), (0.0, 120.5)):
        with pytest.raises(InvalidParameterError, match=r"may only narrow .* 0 \.\. 120 V"):
            model.inverse(voltage_range=wide)


def test_slew_limit_uses_the_reference_files_own_sample_rate(tmp_path):
    hystcomp.save_model(presets.paper_mpi(), tmp_path / "m.json")
    t = np.arange(400) / 2000.0  # 2 kHz, not the 20 kHz default of inverse()
    write_table(tmp_path / "ref.csv", {"t": t, "x": np.where(t < 0.1, 0.0, 30.0)})
    out = tmp_path / "v.csv"
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", out]
    assert run(*args, "--slew-rate", 500).exit_code == 0
    steps = np.abs(np.diff(read_table(out, ("v",))["v"]))
    assert steps.max() == pytest.approx(500.0 / 2000.0, rel=1e-9)  # limiting, at 2 kHz


def test_slew_limit_with_a_given_sample_rate_and_with_uneven_sampling(tmp_path):
    hystcomp.save_model(presets.paper_mpi(), tmp_path / "m.json")
    (tmp_path / "ref.dat").write_text("".join(f"{0.0 if k < 50 else 30.0}\n" for k in range(200)))
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.dat", "--columns", "x=1"]
    assert run(*args, "--fs", 1000, "--slew-rate", 500, "-o", tmp_path / "a.csv").exit_code == 0
    assert np.abs(np.diff(read_table(tmp_path / "a.csv", ("v",))["v"])).max() == pytest.approx(0.5)

    t = np.cumsum(np.r_[0.0, np.tile([1e-3, 3e-3], 100)])  # uneven: 1 ms and 3 ms steps
    write_table(tmp_path / "ref.csv", {"t": t, "x": np.where(t < 0.05, 0.0, 30.0)})
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "b.csv"]
    assert run(*args, "--slew-rate", 500).exit_code == 0
    out = read_table(tmp_path / "b.csv", ("v",))
    rates = np.abs(np.diff(out["v"])) / np.diff(out["t"])
    assert rates.max() <= 500.0 * (1 + 1e-9)  # on every interval, short or long


def test_identify_writes_both_outputs_or_neither(tmp_path, monkeypatch):
    t, v = triangle_sequence(sample_rate=200.0)
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": presets.paper_mpi().simulate(v)})
    model, fig = tmp_path / "m.json", tmp_path / "fig.png"
    model.write_text("earlier model")
    args = ["identify", tmp_path / "rec.csv", "--model", "pi", "--plot", fig, "-o", model]

    def broken_plot(*args, **kwargs):
        raise InvalidParameterError("the figure cannot be drawn")

    with monkeypatch.context() as patch:
        patch.setattr("hystcomp.experiment.fig_identification.plot_identification", broken_plot)
        result = run(*args)
    assert result.exit_code == 2
    assert "the figure cannot be drawn" in result.output
    assert model.read_text() == "earlier model"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json", "rec.csv"]

    result = run(*args)
    assert result.exit_code == 0, result.output
    assert hystcomp.load_model(model).kind == "pi"
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def with_paths(context, body):
    with context as tmps:
        body(*tmps)


def test_a_failed_rename_or_write_leaves_every_file_as_it_was(tmp_path, monkeypatch):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("old a")
    b.write_text("old b")

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    def write_then_fail(tmp_a, _tmp_b):
        tmp_a.write_text("new a")
        full_disk()

    with pytest.raises(OutputPathError, match=r"a\.csv', '.*b\.csv': No space left on device"):
        with_paths(atomic_paths(a, b), write_then_fail)
    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(OutputPathError, match=r"b\.csv"):
        write_table(b, {"t": [0.0, 1.0]})
    monkeypatch.undo()
    assert (a.read_text(), b.read_text()) == ("old a", "old b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


def test_outputs_get_ordinary_permissions(tmp_path):
    """Not the private mode of a temporary file: the umask's, or the replaced file's."""
    umask = os.umask(0o022)
    try:
        write_table(tmp_path / "new.csv", {"t": [0.0, 1.0]})
        (tmp_path / "old.csv").write_text("old")
        (tmp_path / "old.csv").chmod(0o640)
        write_table(tmp_path / "old.csv", {"t": [0.0, 1.0]})
    finally:
        os.umask(umask)
    assert (tmp_path / "new.csv").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "old.csv").stat().st_mode & 0o777 == 0o640


def test_output_path_errors_are_their_own_class(tmp_path):
    with pytest.raises(OutputPathError, match=r"folder '.*nowhere' does not exist") as err:
        write_table(tmp_path / "nowhere" / "x.csv", {"t": [0.0, 1.0]})
    assert isinstance(err.value, ValueError)
    assert isinstance(err.value, HystcompError)
    with pytest.raises(OutputPathError, match="it is a folder"):
        hystcomp.save_model(presets.paper_pi(), tmp_path)


def test_a_link_to_the_input_is_the_input(tmp_path, monkeypatch):
    write_table(tmp_path / "ref.csv", {"t": [0.0, 1.0], "x": [1.0, 2.0]})
    hystcomp.save_model(presets.paper_pi(), tmp_path / "m.json")
    (tmp_path / "link.csv").symlink_to(tmp_path / "ref.csv")
    before = (tmp_path / "ref.csv").read_bytes()
    monkeypatch.chdir(tmp_path)
    for out in (tmp_path / "link.csv", "ref.csv", "./ref.csv"):
        result = run("compensate", "m.json", tmp_path / "ref.csv", "-o", out)
        assert result.exit_code == 2
        assert "it is the input file" in result.output
    assert (tmp_path / "ref.csv").read_bytes() == before


def test_compensate_refuses_a_reference_with_nan_naming_the_row(tmp_path):
    hystcomp.save_model(presets.paper_pi(), tmp_path / "m.json")
    (tmp_path / "ref.csv").write_text("t,x\n0,1\n0.001,2\n0.002,nan\n")
    result = run("compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v.csv")
    assert result.exit_code == 2
    assert "non-finite value (nan) in data row 3" in result.output
    assert not (tmp_path / "v.csv").exists()


def test_closed_standard_output_is_not_an_internal_error(monkeypatch):
    def closed(*args, **kwargs):
        raise BrokenPipeError

    monkeypatch.setattr("hystcomp.io.records.format_csv", closed)  # as `| head` would
    result = run("excite", "pi", "--fs", "10")
    assert result.exit_code == 141
    assert "internal error" not in result.output


@pytest.mark.parametrize("make", [presets.paper_pi, presets.paper_mpi])
def test_stepper_never_commands_nan_for_huge_finite_references(make):
    """A garbage float from a sensor (1e308) overflows inside the chain: the output holds."""
    stepper = make().inverse().stepper()
    outputs = [stepper.step(x) for x in (10.0, 1e308, -1e308, 1e300, 20.0)]
    assert all(0.0 <= v <= 120.0 for v in outputs), outputs
    assert outputs[1] == outputs[0]  # held, like a non-finite reference
    assert stepper.nonfinite_count >= 1
