"""pandas Series and DataFrame columns are accepted wherever arrays are."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hystcomp import ModifiedPrandtlIshlinskii, PrandtlIshlinskii, Record, presets, read_record
from hystcomp.errors import InvalidTypeError
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import write_table


@pytest.fixture(scope="module")
def frame():
    true = presets.paper_mpi()
    t, v = triangle_sequence([30.0, 60.0, 90.0, 120.0], sample_rate=400)
    x = true.simulate(v) + np.random.default_rng(7).normal(0.0, 0.01, v.size)
    # a non-default index: conversion must use positions, not labels
    return pd.DataFrame({"t": t, "v": v, "x": x}, index=np.arange(v.size) + 1000)


def test_fit_simulate_score_take_dataframe_columns(frame):
    model = ModifiedPrandtlIshlinskii(regularization=0.0).fit(frame["v"], frame["x"])
    reference = ModifiedPrandtlIshlinskii(regularization=0.0).fit(
        frame["v"].to_numpy(), frame["x"].to_numpy()
    )
    np.testing.assert_array_equal(model.weights_, reference.weights_)
    x_hat = model.simulate(frame["v"])
    assert isinstance(x_hat, np.ndarray)
    np.testing.assert_array_equal(x_hat, reference.simulate(frame["v"].to_numpy()))
    assert model.score(frame["v"], frame["x"]) > 0.999
    comp = model.inverse()
    np.testing.assert_array_equal(comp.simulate(frame["x"]), comp.simulate(frame["x"].to_numpy()))
    s = comp.stepper()
    np.testing.assert_array_equal(s.step_block(frame["x"]), comp.simulate(frame["x"]))


def test_a_one_column_frame_and_text_columns(frame):
    model = PrandtlIshlinskii().fit(frame[["v"]].squeeze(), frame["x"])
    assert model.score(frame["v"], frame["x"]) > 0.99
    with pytest.raises(InvalidTypeError, match="'v' must be a 1-D array of real numbers"):
        model.simulate(frame["v"].astype(str))


def test_record_to_frame_round_trip(tmp_path, frame):
    path = tmp_path / "rec.csv"
    write_table(path, {k: frame[k] for k in ("t", "v", "x")})
    rec = read_record(path)
    df = rec.to_frame()
    assert list(df.columns) == ["t", "v", "x"]
    assert df.attrs["source"] == str(path)
    np.testing.assert_allclose(df["x"], frame["x"], rtol=1e-12)
    again = Record(df["t"], df["v"], df["x"])
    np.testing.assert_array_equal(again.v, rec.v)
    df.loc[0, "v"] = -1.0  # the frame holds copies
    assert rec.v[0] != -1.0
