"""Edge cases of compensate and export-c: each refused cleanly, or counted and written right."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.codegen import export_c, generate_c
from hystcomp.errors import InvalidParameterError
from hystcomp.io.records import read_table, write_table
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel

FS = 20_000.0


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error(result) -> str:
    """The one error line of a result that exited 2 without a traceback."""
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    errors = [line for line in result.output.splitlines() if line.startswith("hystcomp: error:")]
    assert len(errors) == 1, result.output
    return errors[0]


@pytest.fixture
def files(tmp_path):
    hystcomp.save_model(presets.paper_mpi(), tmp_path / "mpi.json")
    t = np.arange(200) / FS
    write_table(tmp_path / "ref.csv", {"t": t, "x": np.linspace(1.0, 20.0, 200)})
    write_table(tmp_path / "no_t.csv", {"x": np.linspace(1.0, 20.0, 200)})
    return tmp_path


def test_a_prefix_too_long_for_the_file_system_leaves_no_folder(files):
    out = files / "firmware"
    line = one_error(run("export-c", files / "mpi.json", "-o", out, "--prefix", "a" * 300))
    assert "File name too long" in line
    assert not out.exists()
    # an existing folder stays, and nothing is added to it
    out.mkdir()
    one_error(run("export-c", files / "mpi.json", "-o", out, "--prefix", "a" * 300))
    assert list(out.iterdir()) == []


def test_a_sample_rate_whose_times_no_reader_takes_is_refused(files):
    out = files / "v.csv"
    line = one_error(
        run("compensate", files / "mpi.json", files / "no_t.csv", "--fs", 1e-306, "-o", out)
    )
    assert "The sample rate 1e-306 Hz (--fs" in line
    assert "inf s, beyond the 1e+12 s a time column may hold" in line
    assert not out.exists()
    # the slowest rate whose times a file can hold: written, and read back
    assert (
        run("compensate", files / "mpi.json", files / "no_t.csv", "--fs", 1e-9, "-o", out).exit_code
        == 0
    )
    t = read_table(out, ("v",))["t"]
    assert t[-1] == pytest.approx(199e9)


def test_a_tiny_step_of_the_time_column_with_a_slew_rate_names_the_row(files):
    t = np.arange(200) / FS
    t[1] = 1e-300
    write_table(files / "tiny.csv", {"t": t, "x": np.linspace(1.0, 20.0, 200)})
    out = files / "v.csv"
    line = one_error(
        run("compensate", files / "mpi.json", files / "tiny.csv", "--slew-rate", 1e3, "-o", out)
    )
    assert "time column 't' of" in line
    assert "steps by only 1e-300 s from t = 0.0 to 1e-300 s (data row 2)" in line
    assert "sample_rate" not in line  # no internal parameter
    assert not out.exists()
    # a jittery column is no fault: the limit holds on its shortest step
    t = np.arange(200) / FS
    t[1::2] += 0.2 / FS
    write_table(files / "jitter.csv", {"t": t, "x": np.linspace(1.0, 20.0, 200)})
    result = run(
        "compensate", files / "mpi.json", files / "jitter.csv", "--slew-rate", 1e4, "-o", out
    )
    assert result.exit_code == 0, result.output
    v = read_table(out, ("v",))["v"]
    assert np.abs(np.diff(v)).max() == pytest.approx(1e4 * 0.8 / FS)  # the shortest step


def test_the_look_ahead_is_not_counted_as_clamped(files):
    dyn = LinearDynamics.from_parameters(sample_rate=FS, resonance_hz=630.0, damping_ratio=0.1)
    hystcomp.save_model(dyn, files / "dyn.json")
    t = np.arange(2000) / FS
    write_table(files / "far.csv", {"t": t, "x": np.full(2000, 100.0)})  # out of reach
    out = files / "v.csv"
    result = run(
        "compensate",
        files / "mpi.json",
        files / "far.csv",
        "--dynamics",
        files / "dyn.json",
        "-o",
        out,
    )
    assert result.exit_code == 0, result.output
    assert "2000 of 2000 samples (100 %) are out of reach" in result.output
    assert "2000 clamped" in result.output
    compensator = HammersteinModel(presets.paper_mpi(), dyn).inverse()
    stepper = compensator.stepper()
    stepper.prime(np.full(compensator.preview, 100.0))
    assert stepper.clamped_count == 0  # outputs before time 0 are never applied
    assert compensator.run(np.full(50, 100.0)).clamped == 50


def test_export_c_narrows_the_clamp_of_any_model(files):
    hystcomp.save_model(presets.paper_preisach(), files / "p.json")
    out = files / "fw"
    result = run("export-c", files / "p.json", "-o", out, "--voltage-range", 10, 100)
    assert result.exit_code == 0, result.output
    source = (out / "hystcomp_compensator.c").read_text()
    assert "if (v < 10.0)" in source
    assert "if (v > 100.0)" in source
    line = one_error(
        run("export-c", files / "p.json", "-o", files / "fw2", "--voltage-range", 10, 130)
    )
    assert "'--voltage-range': may only narrow the model's voltage range 0 .. 120 V" in line
    assert not (files / "fw2").exists()


def test_identify_s_advice_for_a_narrow_preisach_clamp_is_an_option_that_exists(files):
    from hystcomp.identify.excitation import triangle_sequence

    t, v = triangle_sequence(sample_rate=1000.0)
    write_table(files / "rec.csv", {"t": t, "v": v, "x": presets.paper_mpi().simulate(v)})
    args = ("identify", files / "rec.csv", "--model", "preisach", "--voltage-range", 10, 100)
    line = one_error(run(*args, "-o", files / "m.json"))
    assert "--voltage-range of compensate and export-c" in line
    export = main.get_command(None, "export-c")
    assert "--voltage-range" in [opt for p in export.params for opt in p.opts]


def test_python_export_refuses_a_rate_other_than_the_dynamics(tmp_path):
    dyn = LinearDynamics.from_parameters(sample_rate=FS, resonance_hz=630.0, damping_ratio=0.1)
    compensator = HammersteinModel(presets.paper_mpi(), dyn).inverse()
    with pytest.raises(
        InvalidParameterError, match=r"\(1000 Hz\) differs from the rate of .* \(20000 Hz\)"
    ):
        export_c(compensator, tmp_path / "fw", sample_rate=1000)
    assert not (tmp_path / "fw").exists()
    slow = LinearDynamics.from_parameters(sample_rate=5000.0, resonance_hz=600.0, damping_ratio=0.1)
    header, _ = generate_c(HammersteinModel(presets.paper_mpi(), slow).inverse(slew_rate=5e3))
    assert "(5000 V/s at 5000 Hz)" in header  # the rate by default: the dynamics'


@pytest.mark.parametrize("value", [(False, True), ("0", "100"), (0.0, True), "01"])
def test_a_voltage_range_of_booleans_or_text_is_not_a_range(value):
    for model in (presets.paper_mpi(), presets.paper_preisach()):
        with pytest.raises(
            InvalidParameterError, match="must be a pair \\(low, high\\) of numbers"
        ):
            model.inverse(voltage_range=value)
    assert presets.paper_mpi().inverse(voltage_range=(np.int64(10), 100.0)).voltage_range == (
        10.0,
        100.0,
    )
