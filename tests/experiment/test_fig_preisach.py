"""Fig. 5: the Preisach model's loops for 1 Hz sinusoids of 30, 60, 90 and 120 V."""

import numpy as np
import pytest

from hystcomp import presets
from hystcomp.errors import InvalidParameterError, OutputPathError
from hystcomp.experiment.fig_preisach import plot_preisach_loops
from hystcomp.identify.excitation import sinusoid_sequence


def test_writes_a_png_with_measured_data_underneath(tmp_path):
    model = presets.paper_preisach()
    _, v = sinusoid_sequence([30.0, 60.0, 90.0, 120.0], sample_rate=500.0)
    x = presets.paper_preisach(zero_diagonal=True).simulate(v)
    path = tmp_path / "fig5.png"
    plot_preisach_loops(model, path, measured=(v, x), sample_rate=500.0)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 20_000  # axes, four loops, labels and legend, not an empty canvas
    assert [p.name for p in tmp_path.iterdir()] == ["fig5.png"]


def test_bad_arguments_are_refused_without_writing(tmp_path):
    model = presets.paper_preisach()
    with pytest.raises(InvalidParameterError, match=r"'amplitudes'"):
        plot_preisach_loops(model, tmp_path / "a.png", amplitudes=[])
    with pytest.raises(ValueError, match=r"same length"):
        plot_preisach_loops(model, tmp_path / "b.png", measured=(np.zeros(3), np.zeros(4)))
    with pytest.raises(OutputPathError, match=r"does not exist"):
        plot_preisach_loops(model, tmp_path / "missing" / "c.png")
    assert list(tmp_path.iterdir()) == []
