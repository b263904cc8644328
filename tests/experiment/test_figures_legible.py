"""The figures are legible: a long record as excerpts over its error in time, the hold-out
prediction shown, every panel's lines told apart by a legend, labels written alike."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hystcomp import presets
from hystcomp.experiment import fig_dynamics, fig_identification, fig_preisach
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import read_record
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.workflows.identify import identify_record

REAL_RECORD = Path(__file__).parents[1] / "data" / "piezo-micromanipulator" / "Model_Vi_Do.dat"


@pytest.fixture
def drawn(monkeypatch):
    """The figures the modules save, kept instead of written."""
    figures = []

    def keep(fig, path, *, dpi):
        figures.append(fig)

    for module in (fig_identification, fig_dynamics, fig_preisach):
        monkeypatch.setattr(module, "save_figure", keep)
    return figures


def _labels(ax) -> list[str]:
    return [line.get_label() for line in ax.get_lines() if not line.get_label().startswith("_")]


def test_a_long_record_with_a_hold_out_is_drawn_as_excerpts_over_its_error(drawn):
    rec = read_record(REAL_RECORD, columns="v=1,x=5", sample_rate=200.0)  # 40 s, 40 loops
    result = identify_record(rec, ModifiedPrandtlIshlinskii(), holdout=0.5)
    fig_identification.plot_identification_result(rec, result, "fig.png")
    (fig,) = drawn
    loops_a, loops_b, errors = fig.axes
    # (b) shows the prediction on the hold-out: the model run on, from where the fit ended
    (predicted,) = [
        ln for ln in loops_b.get_lines() if "predicted on the hold-out" in ln.get_label()
    ]
    whole = result.model.simulate(rec.v)
    y = predicted.get_ydata()
    start = result.n_fit
    np.testing.assert_array_equal(y, whole[start : start + y.size])
    # the loops are excerpts of two loops each, not the 8000 samples laid over each other
    for line in loops_a.get_lines() + loops_b.get_lines():
        assert line.get_xdata().size < len(rec) // 8
    assert fig_identification.turning_points(loops_b.get_lines()[0].get_xdata()).size <= 5
    # (c) the error over the whole record, fitted and held out, each with its rms
    labels = _labels(errors)
    assert labels[0].startswith("fitted: rms")
    assert labels[1].startswith("hold-out (predicted)")
    t = np.concatenate([line.get_xdata() for line in errors.get_lines()[:2]])
    assert t.min() <= rec.t[result.start] + 0.01
    assert t.max() >= rec.t[-1] - 0.01
    hold_rms = float(np.sqrt(np.mean((whole[start:] - rec.x[start:]) ** 2)))
    assert f"rms {hold_rms:.3g} µm" in labels[1]
    assert errors.get_lines()[0].get_xdata().size < 4 * 2000  # an envelope per pixel column


def test_a_short_record_is_drawn_whole_as_the_paper_does(drawn):
    _, v = triangle_sequence(sample_rate=500.0)  # the paper's 4 s of triangles
    x = presets.paper_mpi().simulate(v)
    fig_identification.plot_identification(v, x, 0.3 * v, x, "fig.png", model_name="MPI")
    (fig,) = drawn
    assert len(fig.axes) == 2
    assert fig.axes[1].get_title() == "(b) after identification (MPI)"


def test_turning_points_and_excerpts_of_two_loops():
    v = np.tile(np.r_[np.linspace(0.0, 10.0, 50), np.linspace(10.0, 0.0, 50)[1:-1]], 6)
    v = v + 0.01 * np.random.default_rng(0).standard_normal(v.size)  # noise below the tolerance
    turns = fig_identification.turning_points(v)
    assert turns.size == 11  # 6 maxima and 5 minima inside, none from the noise
    window = fig_identification._excerpt(turns, 0, v.size, at_end=True)
    assert window.stop == v.size
    assert np.count_nonzero((turns > window.start) & (turns < window.stop)) == 4


def test_step_and_hold_has_a_legend_in_each_panel_and_no_line_hides_another(drawn):
    t = np.arange(20_000) / 2e4
    x_ref = np.where(t > 0.05, 10.0, 0.0)
    ring = np.where(t > 0.05, np.exp(-(t - 0.05) * 300) * np.cos(4e3 * (t - 0.05)), 0.0)
    runs = {
        "preisach": x_ref + 5 * ring,
        "preisach + dynamics": x_ref + 0.5 * ring,
        "mpi": x_ref + 5 * ring,  # the same ringing: drawn over the Preisach run
        "mpi + dynamics": x_ref + 0.5 * ring,
    }
    fig_dynamics.plot_step(t, x_ref, runs, "step.png")
    (fig,) = drawn
    for ax in fig.axes:
        assert ax.get_legend() is not None
        assert [t.get_text() for t in ax.get_legend().get_texts()] == [
            "Preisach",
            "Preisach + dynamics",
            "MPI",
            "MPI + dynamics",
        ]
        lines = ax.get_lines()[:4]
        widths = [line.get_linewidth() for line in lines]
        assert widths == sorted(widths, reverse=True)  # each drawn thinner over the one before
        assert widths[0] > widths[2] + 1.0  # the covered run shows on both sides of the other
        assert [line.get_linestyle() for line in lines] == ["-", "--", "-", "--"]


def test_axis_labels_are_written_alike_in_every_figure(drawn):
    fig_preisach.plot_preisach_loops(presets.paper_preisach(), "fig5.png")
    _, v = triangle_sequence(sample_rate=500.0)
    x = presets.paper_mpi().simulate(v)
    fig_identification.plot_identification(v, x, 0.3 * v, x, "fig8.png")
    labels = [
        text
        for fig in drawn
        for ax in fig.axes
        for text in (ax.get_xlabel(), ax.get_ylabel())
        if text
    ]
    assert "voltage v_px (V)" in labels  # Fig. 5, as the paper names the piezo voltage
    assert all(text[0].islower() for text in labels), labels
