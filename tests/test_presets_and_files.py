"""The paper's identified models and the model file round trip."""

import json

import numpy as np
import pytest

import hystcomp
from hystcomp import paper, presets
from hystcomp.errors import ModelFileError
from tests.conftest import random_walk


def test_pi_preset_is_eq_20_in_micrometres_per_volt():
    model = presets.paper_pi()
    assert model.weights_[0] == pytest.approx(0.1386)
    assert model.thresholds_[1] == pytest.approx(7.5)  # eq. (16): 120 / 16
    np.testing.assert_array_equal(model.weights_, paper.PI_WEIGHTS)
    # from rest (eq. 18: every play at 0) up to 120 V, play i outputs 120 - r_i (eq. 11), so
    # eq. (12) gives sum_i w_i (120 - 7.5 i), with the printed weights of eq. (20)
    stroke = sum(w * (120.0 - 7.5 * i) for i, w in enumerate(paper.PI_WEIGHTS))
    assert model.simulate([0.0, 120.0])[-1] == pytest.approx(stroke, rel=1e-12)
    assert stroke == pytest.approx(37.8, abs=0.05)  # the stroke the presets' notes quote


def test_mpi_preset_max_displacement_is_the_fixed_point():
    m = presets.PAPER_MPI_MAX_DISPLACEMENT
    v = presets.paper_identification_triangle()
    assert presets.paper_mpi_with(m).simulate(v).max() == pytest.approx(m, abs=1e-9)
    # and the inverse dead-zone thresholds of eq. (17) are recovered from the forward ones
    mpi = presets.paper_mpi()
    r_inv, w_inv = hystcomp.ModifiedPrandtlIshlinskii.forward_deadzones(
        mpi.deadzone_thresholds_, mpi.deadzone_weights_
    )
    np.testing.assert_allclose(r_inv, np.arange(16) / 16 * m, atol=1e-9)
    np.testing.assert_allclose(w_inv, presets.PAPER_MPI_INVERSE_DEADZONE_WEIGHTS, atol=1e-12)


@pytest.mark.parametrize("make", [presets.paper_pi, presets.paper_mpi])
def test_json_round_trip_reproduces_output_exactly(make, tmp_path, rng):
    model = make()
    path = tmp_path / "model.json"
    hystcomp.save_model(model, path)
    doc = json.loads(path.read_text())
    assert (doc["format"], doc["version"]) == ("hystcomp-model", 1)
    loaded = hystcomp.load_model(path)
    v = random_walk(rng, 2000, 0, 120, 8.0)
    assert np.array_equal(loaded.simulate(v), model.simulate(v))
    x = model.simulate(v)
    assert np.array_equal(loaded.inverse().simulate(x), model.inverse().simulate(x))
    # hand-edited in an editor that adds a UTF-8 byte-order mark: still the same model
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert np.array_equal(hystcomp.load_model(path).simulate(v), model.simulate(v))


def test_failed_save_leaves_existing_file(tmp_path):
    path = tmp_path / "model.json"
    path.write_text("precious")
    with pytest.raises(Exception, match="hystcomp's models"):
        hystcomp.save_model(object(), path)
    assert path.read_text() == "precious"
    assert list(tmp_path.iterdir()) == [path]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("not json", r"not valid JSON"),
        ('{"format": "other"}', r"not a hystcomp model file"),
        ('{"format": "hystcomp-model", "version": 99, "kind": "pi"}', r"newer than this"),
        (
            '{"format": "hystcomp-model", "version": 1, "kind": "bogus", "parameters": {}}',
            r"model kind 'bogus'",
        ),
        (
            '{"format": "hystcomp-model", "version": 1, "kind": "pi", "parameters": {}}',
            r'no "thresholds" in its parameters',
        ),
        (
            (
                '{"format": "hystcomp-model", "version": 1, "kind": "pi", '
                '"parameters": {"thresholds": [0, 1], "weights": [1, "x"]}}'
            ),
            r"the text 'x' at parameters\[\"weights\"\]\[1\]",
        ),
    ],
)
def test_bad_model_files_are_refused_clearly(tmp_path, content, message):
    path = tmp_path / "m.json"
    path.write_text(content)
    with pytest.raises(ModelFileError, match=message):
        hystcomp.load_model(path)
