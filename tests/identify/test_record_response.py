"""Every fit refuses a record whose displacement does not respond to its input (one check,
:func:`hystcomp.identify.scoring.check_response`, shared by PI, MPI and Preisach)."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import IdentificationError
from hystcomp.identify.excitation import sinusoid_sequence, triangle_sequence
from hystcomp.identify.scoring import MIN_EXPLAINED, check_response
from hystcomp.io.records import write_table

FITS = {
    "pi": lambda: hystcomp.PrandtlIshlinskii(n_operators=8),
    "mpi": lambda: hystcomp.ModifiedPrandtlIshlinskii(n_operators=8, n_deadzones=4),
    "preisach": lambda: hystcomp.Preisach(),
}


def _signal(kind):
    if kind == "preisach":
        return sinusoid_sequence([20.0, 40.0, 60.0, 80.0, 100.0, 120.0], sample_rate=400.0)[1]
    return triangle_sequence((60.0, 120.0), sample_rate=400.0)[1]


def _true_x(kind, v):
    return (presets.paper_preisach() if kind == "preisach" else presets.paper_pi()).simulate(v)


@pytest.mark.parametrize("kind", sorted(FITS))
@pytest.mark.parametrize("what", ["zeros", "noise", "offset noise"])
def test_every_fit_refuses_a_displacement_that_does_not_respond(kind, what, rng):
    v = _signal(kind)
    x = {
        "zeros": np.zeros(v.size),
        "noise": 0.01 * rng.standard_normal(v.size),
        "offset noise": -120.0 + 2.0 * rng.standard_normal(v.size),
    }[what]
    match = "is constant" if what == "zeros" else "does not respond"
    with pytest.raises(IdentificationError, match=match):
        FITS[kind]().fit(v, x)


@pytest.mark.parametrize("kind", sorted(FITS))
def test_a_noisy_response_is_still_identified(kind, rng):
    v = _signal(kind)
    x = _true_x(kind, v)
    noise = 0.05 * np.ptp(x)  # rms, 5 % of the stroke
    model = FITS[kind]().fit(v, x + noise * rng.standard_normal(v.size))
    # the model found is the response under the noise: it misses the noisy record by the
    # noise, and the noise-free response by much less (the noise averages out in the fit)
    assert model.fit_report_["rms_error_um"] == pytest.approx(noise, rel=0.1)
    assert np.sqrt(np.mean((model.simulate(v) - x) ** 2)) < 0.5 * noise


def test_short_noise_is_refused_even_when_a_line_explains_much(rng):
    # 10 samples of noise often reach R^2 > MIN_EXPLAINED by chance: the F test refuses them
    v = np.linspace(0.0, 120.0, 10)
    x = 0.2 * v + rng.standard_normal(10)
    check_response(v, x, "fit")  # a real response, 10 samples
    for seed in range(200):
        noise = np.random.default_rng(seed).standard_normal(10)
        r2 = np.corrcoef(v, noise)[0, 1] ** 2
        if r2 >= MIN_EXPLAINED:
            with pytest.raises(IdentificationError, match="does not respond"):
                check_response(v, noise, "fit")
            return
    pytest.fail("no seed gave a chance R^2 above the threshold")


def test_cli_refuses_an_all_zero_preisach_record(tmp_path):
    v = _signal("preisach")
    write_table(tmp_path / "r.csv", {"t": np.arange(v.size) / 400.0, "v": v, "x": 0.0 * v})
    result = CliRunner().invoke(
        main,
        ["identify", str(tmp_path / "r.csv"), "--model", "preisach", "-o", str(tmp_path / "m")],
    )
    assert result.exit_code == 2, result.output
    assert "hystcomp: error:" in result.stderr
    assert "is constant" in result.stderr
    assert not (tmp_path / "m").exists()
