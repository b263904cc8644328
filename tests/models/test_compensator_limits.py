"""A compensator never surprises the actuator: clamping is counted and told, the held value
on a non-finite sample is inside the range from the first sample, and no model commands a
voltage its record never reached."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import read_table, write_table
from tests.codegen.test_codegen import _compile, _run_c, needs_cc

COMPENSATORS = {
    "pi": (presets.paper_pi, {}),
    "mpi": (presets.paper_mpi, {}),
    "preisach": (presets.paper_preisach, {"method": "multiplicative"}),
    "preisach-exact": (presets.paper_preisach, {"method": "exact"}),
}


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _loop(model, n=300):
    lo, hi = model.voltage_range_
    up = np.linspace(lo, hi, n)
    v = np.r_[up, up[::-1], up[: n // 2]]
    return model.simulate(v)


@pytest.mark.parametrize("name", sorted(COMPENSATORS))
def test_run_counts_no_clamp_on_a_reachable_reference(name):
    make, options = COMPENSATORS[name]
    model = make()
    comp = model.inverse(**options)
    x_ref = _loop(model)
    result = comp.run(x_ref)
    assert result.clamped == 0
    assert result.nonfinite == 0
    np.testing.assert_array_equal(result.v, comp.simulate(x_ref))


@pytest.mark.parametrize("name", sorted(COMPENSATORS))
def test_run_counts_every_sample_out_of_reach(name, rng):
    make, options = COMPENSATORS[name]
    model = make()
    comp = model.inverse(**options)
    x_lo, x_hi = model.reachable_range()
    inside = _loop(model)  # reachable; then out of reach on both sides, then a rise from lo
    # held levels: a reference that wanders out there moves the inverse's own plays, and a
    # step back towards the range may then be reachable from that state
    above = np.full(70, x_hi + rng.uniform(0.5, 20.0))
    below = np.full(30, x_lo - rng.uniform(0.5, 20.0))
    lo, hi = model.voltage_range_
    rise = model.simulate(np.linspace(lo, lo + 0.8 * (hi - lo), 200))
    x_ref = np.r_[inside, above, below, rise]
    result = comp.run(x_ref)
    lo, hi = comp.voltage_range
    assert result.clamped == 100
    assert result.clamped_share == pytest.approx(100 / x_ref.size)
    n = inside.size
    assert np.all(result.v[n : n + 70] == hi)
    assert np.all(result.v[n + 70 : n + 100] == lo)
    stepper = comp.stepper()
    for x in x_ref:
        stepper.step(x)
    assert stepper.clamped_count == 100
    stepper.reset()
    assert stepper.clamped_count == 0


@pytest.mark.parametrize("name", sorted(COMPENSATORS))
def test_narrowed_range_counts_what_it_cuts(name):
    make, options = COMPENSATORS[name]
    model = make()
    comp = model.inverse(voltage_range=(10.0, 50.0), **options)
    x_lo, x_hi = model.reachable_range(voltage_range=(10.0, 50.0))
    full_lo, full_hi = model.reachable_range()
    assert full_lo < x_lo < x_hi < full_hi
    result = comp.run(_loop(model))
    assert 0 < result.clamped < result.v.size
    assert result.v.min() >= 10.0
    assert result.v.max() <= 50.0


def test_reachable_range_is_the_major_loop():
    model = presets.paper_pi()
    x_lo, x_hi = model.reachable_range()
    x = model.simulate(np.linspace(0.0, 120.0, 1001))
    assert x_lo == pytest.approx(x.min())
    assert x_hi == pytest.approx(x.max())


@pytest.mark.parametrize("name", sorted(COMPENSATORS))
def test_a_first_nan_holds_a_voltage_inside_a_narrowed_range(name):
    make, options = COMPENSATORS[name]
    comp = make().inverse(voltage_range=(10.0, 50.0), **options)
    assert comp.stepper().step(float("nan")) == 10.0
    assert comp.stepper().last_output == 10.0
    block = comp.stepper().step_block(np.array([np.nan, np.inf, np.nan]))
    np.testing.assert_array_equal(block, [10.0, 10.0, 10.0])


@needs_cc
@pytest.mark.parametrize("name", sorted(COMPENSATORS))
def test_a_first_nan_in_c_holds_a_voltage_inside_a_narrowed_range(name, tmp_path):
    make, options = COMPENSATORS[name]
    comp = make().inverse(voltage_range=(10.0, 50.0), **options)
    x_ref = np.array([np.nan, np.nan, 5.0])
    drive = _compile(comp, tmp_path, "comp") if "preisach" not in name else None
    if drive is None:
        from tests.codegen.test_codegen import _compile_preisach

        v, _depth, held = _compile_preisach(comp, tmp_path)(x_ref)
    else:
        v, held = _run_c(drive, x_ref)
    assert held == 2
    assert v[0] == v[1] == 10.0
    assert 10.0 <= v[2] <= 50.0
    stepper = comp.stepper()  # and sample for sample the Python stepper's voltages
    np.testing.assert_array_equal(v, [stepper.step(x) for x in x_ref])
    assert stepper.nonfinite_count == held


def _files(tmp_path, model, x_ref):
    hystcomp.save_model(model, tmp_path / "m.json")
    write_table(tmp_path / "ref.csv", {"t": np.arange(x_ref.size) / 1e3, "x": x_ref})
    return tmp_path / "m.json", tmp_path / "ref.csv", tmp_path / "v.csv"


def _offset_pi():
    """A model whose displacement is -123 .. -74 µm on a 0 .. 3.6 V command (a real record)."""
    base = presets.paper_pi()
    return hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=base.thresholds_ * 0.03,
        weights=base.weights_ / 0.03 * 1.3,
        voltage_range=(0.0, 3.6),
        output_offset=-123.0,
    )


def test_cli_warns_once_with_count_share_and_reachable_range(tmp_path):
    model = _offset_pi()
    x_lo, x_hi = model.reachable_range()
    model_file, ref, out = _files(tmp_path, model, np.linspace(0.0, 40.0, 400))
    result = CliRunner().invoke(main, ["compensate", str(model_file), str(ref), "-o", str(out)])
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if line.startswith("hystcomp:")]
    assert len(warnings) == 1
    line = warnings[0]
    assert line.startswith("hystcomp: warning: 400 of 400 samples (100 %)")
    assert f"{x_lo:.4g} .. {x_hi:.4g} µm" in line
    assert np.all(read_table(out, ("v",))["v"] == 3.6)


def test_cli_strict_refuses_and_writes_nothing(tmp_path):
    model = _offset_pi()
    x_lo, x_hi = model.reachable_range()
    x_ref = np.r_[np.linspace(x_lo, x_hi, 300), x_hi + 1.0]
    model_file, ref, out = _files(tmp_path, model, x_ref)
    out.write_text("old\n")
    result = CliRunner().invoke(
        main, ["compensate", str(model_file), str(ref), "-o", str(out), "--strict"]
    )
    assert result.exit_code == 2, result.output
    assert "1 of 301 samples" in result.stderr
    assert out.read_text() == "old\n"


def test_cli_names_the_ends_that_a_swing_leaves_when_loops_do_not_close(tmp_path):
    """The paper's PI model starts virgin at 0 µm, but after a swing over 0..120 V it comes
    back to 0 V above that: a reference down to 0 µm after a swing is out of reach, though
    inside the model's extremes. The message names the ends after the swing."""
    model = presets.paper_pi()
    x_lo, x_hi = model.reachable_range()
    swung = model.simulate(np.array([0.0, 120.0, 0.0]))[-1]
    assert swung > x_lo + 0.5
    x_ref = np.r_[np.linspace(0.0, 0.9 * x_hi, 200), np.linspace(0.9 * x_hi, x_lo, 200)]
    model_file, ref, out = _files(tmp_path, model, x_ref)
    args = ["compensate", str(model_file), str(ref), "-o", str(out), "--strict"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2
    assert f"the model reaches {x_lo:.4g} .. {x_hi:.4g} µm, but after a swing" in result.stderr
    assert f"shift or scale the reference into {swung:.4g} .. {x_hi:.4g} µm" in result.stderr


@pytest.mark.parametrize("strict", [False, True])
def test_cli_reachable_reference_gives_no_warning(tmp_path, strict):
    model = presets.paper_mpi()
    model_file, ref, out = _files(tmp_path, model, _loop(model))
    args = ["compensate", str(model_file), str(ref), "-o", str(out)]
    result = CliRunner().invoke(main, args + (["--strict"] if strict else []))
    assert result.exit_code == 0, result.output
    assert "warning" not in result.stderr
    assert "0 clamped" in result.stdout


def _record(tmp_path, v_max=120.0):
    t, v = triangle_sequence((0.5 * v_max, v_max), sample_rate=200.0)
    x = presets.paper_pi().simulate(v)
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": x})
    return tmp_path / "rec.csv"


def test_identify_refuses_a_voltage_range_wider_than_the_record(tmp_path):
    rec = _record(tmp_path)
    args = ["identify", rec, "--model", "pi", "-o", tmp_path / "m.json"]
    result = run(*args, "--voltage-range", 0, 200)
    assert result.exit_code == 2, result.output
    assert "--allow-extrapolation" in result.output
    assert not (tmp_path / "m.json").exists()
    assert run(*args, "--voltage-range", 0, 200, "--allow-extrapolation").exit_code == 0
    assert hystcomp.load_model(tmp_path / "m.json").voltage_range_ == (0.0, 200.0)
    assert run(*args, "--voltage-range", 10, 100).exit_code == 0  # narrower: the clamp
    comp = hystcomp.load_model(tmp_path / "m.json").inverse()
    assert comp.simulate([1e3]).max() == 100.0
    assert "refused, not capped" in " ".join(run("identify", "--help").output.split())


@pytest.mark.parametrize("make", [presets.paper_pi, presets.paper_mpi, _offset_pi])
@pytest.mark.parametrize("huge", [1e151, 1e308, -1e308])
def test_a_reference_near_the_float_range_is_held_like_nan(make, huge):
    """Such a sample is held and counted as non-finite, and the plays stay where they were:
    what follows is what follows a NaN (before, the plays moved to it while the output was
    held, and the compensator no longer followed what the amplifier had been given)."""
    comp = make().inverse()  # (batch runs refuse such references; a stepper holds them)
    lo, hi = comp.voltage_range
    x = make().simulate(np.linspace(lo, 0.6 * hi + 0.4 * lo, 50))
    with_huge, with_nan = comp.stepper(), comp.stepper()
    v_huge = with_huge.step_block(np.r_[x, huge, x[::-1]])
    v_nan = with_nan.step_block(np.r_[x, np.nan, x[::-1]])
    np.testing.assert_array_equal(v_huge, v_nan)
    assert with_huge.nonfinite_count == 1
    assert with_huge.clamped_count == with_nan.clamped_count
