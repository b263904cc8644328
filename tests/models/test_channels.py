"""Many channels at once: the bank equals each channel's own chain, in batch and streaming."""

from __future__ import annotations

import joblib
import numpy as np
import pytest

import hystcomp
from hystcomp.errors import InvalidSignalError, InvalidTypeError
from hystcomp.models.channels import ChannelBank, fit_channels
from tests.conftest import random_walk


def _models(n, seed=0):
    """PI (15 plays) and MPI (16 + 16) channels, each with its own jittered weights."""
    rng = np.random.default_rng(seed)
    pi, mpi = hystcomp.presets.paper_pi(), hystcomp.presets.paper_mpi()
    out = []
    for c in range(n):
        if c % 3 == 0:
            out.append(
                hystcomp.PrandtlIshlinskii.from_parameters(
                    thresholds=pi.thresholds_[:15],
                    weights=pi.weights_[:15] * rng.uniform(0.9, 1.1, 15),
                    voltage_range=(0.0, 120.0),
                )
            )
        else:
            out.append(
                hystcomp.ModifiedPrandtlIshlinskii.from_parameters(
                    thresholds=mpi.thresholds_,
                    weights=mpi.weights_ * rng.uniform(0.9, 1.1, mpi.weights_.size),
                    deadzone_thresholds=mpi.deadzone_thresholds_,
                    deadzone_weights=mpi.deadzone_weights_,
                    voltage_range=(0.0, 120.0),
                )
            )
    return out


def _references(rng, n, channels, hi=30.0):
    return np.column_stack([random_walk(rng, n, -2.0, hi, 0.4) for _ in range(channels)])


@pytest.mark.parametrize("slew_rate", [None, 3e4])
def test_compensators_agree_with_each_channels_own_chain(slew_rate, rng):
    models = _models(70)
    comps = [m.inverse(slew_rate=slew_rate) for m in models]
    bank = ChannelBank(comps)
    assert bank.n_groups == 2  # PI and MPI: one kernel call each
    X = _references(rng, 3000, 70)
    X[50, 3] = np.nan
    X[70, 4] = np.inf
    stepper = bank.stepper()
    out = stepper.step_block(X)
    own = [c.stepper() for c in comps]
    ref = np.column_stack([s.step_block(X[:, i]) for i, s in enumerate(own)])
    assert np.abs(out - ref).max() <= 1e-12 * 120.0  # the same formulas; sums in another order
    assert np.array_equal(stepper.clamped_count, [s.clamped_count for s in own])
    assert np.array_equal(stepper.nonfinite_count, [s.nonfinite_count for s in own])
    assert stepper.clamped_count.sum() > 0
    assert out.min() >= 0.0
    assert out.max() <= 120.0


def test_models_agree_with_each_channels_own_run(rng):
    models = _models(20, seed=1)
    V = np.column_stack([random_walk(rng, 2000, 0.0, 120.0, 3.0) for _ in range(20)])
    out = ChannelBank(models).simulate(V)
    ref = np.column_stack([m.simulate(V[:, i]) for i, m in enumerate(models)])
    assert np.abs(out - ref).max() <= 1e-12 * np.abs(ref).max()


def test_a_step_equals_the_batch_bit_for_bit_and_state_round_trips(rng):
    bank = ChannelBank([m.inverse() for m in _models(130, seed=2)])  # three channel blocks
    X = _references(rng, 200, 130)
    batch = bank.stepper().step_block(X)
    s = bank.stepper()
    stepped = np.array([s.step(row) for row in X[:100]])
    assert np.array_equal(stepped, batch[:100])
    saved, twin = s.state, s.copy()
    rest = np.array([s.step(row) for row in X[100:]])
    assert np.array_equal(rest, batch[100:])
    assert np.array_equal(np.array([twin.step(row) for row in X[100:]]), rest)
    s.state = saved
    assert np.array_equal(s.step(X[100]), batch[100])
    s.reset()
    assert np.array_equal(s.step(X[0]), batch[0])


def test_a_bank_refuses_preisach_channels_and_mixed_kinds():
    with pytest.raises(InvalidTypeError, match="PI and MPI"):
        ChannelBank([hystcomp.presets.paper_preisach().inverse()])
    pi = hystcomp.presets.paper_pi()
    with pytest.raises(InvalidTypeError, match="mixes models and compensators"):
        ChannelBank([pi, pi.inverse()])


def test_a_step_of_the_wrong_width_is_refused():
    s = ChannelBank([hystcomp.presets.paper_pi().inverse()] * 4).stepper()
    with pytest.raises(InvalidSignalError, match="one value per channel"):
        s.step([1.0, 2.0])


def _records(n_channels, seed=3):
    from hystcomp.identify.excitation import random_turning_points
    from hystcomp.plant import Twin, TwinParameters

    _, v = random_turning_points(16, sample_rate=2000.0, seed=seed)
    V = np.column_stack([v] * n_channels)
    X = np.column_stack(
        [
            Twin(TwinParameters(hysteresis_amplitude=2.0 + 0.2 * c), seed=c).run(v)
            for c in range(n_channels)
        ]
    )
    return V, X


def test_fit_channels_in_threads_equals_one_at_a_time():
    V, X = _records(3)
    one = fit_channels(V, X, family="pi")
    with joblib.parallel_config(backend="threading"):
        many = fit_channels(V, X, family="pi", n_jobs=2)
    for a, b in zip(one, many, strict=True):
        assert np.array_equal(a.weights_, b.weights_)
    # each channel its own model: the hysteresis amplitudes differ, so do the weights
    assert not np.array_equal(one[0].weights_, one[2].weights_)
    bank = ChannelBank([m.inverse() for m in one])
    assert bank.n_channels == 3


@pytest.mark.slow
def test_fit_channels_in_processes():
    V, X = _records(4)
    models = fit_channels(V, X, family="mpi", n_jobs=2)  # loky: worker processes
    assert [m.kind for m in models] == ["mpi"] * 4
    assert np.array_equal(models[1].weights_, fit_channels(V[:, 1:2], X[:, 1:2])[0].weights_)


@pytest.mark.slow
def test_fit_channels_on_a_local_dask_cluster():
    distributed = pytest.importorskip("dask.distributed")
    V, X = _records(4)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster,
        distributed.Client(cluster),
        joblib.parallel_config(backend="dask"),
    ):
        models = fit_channels(V, X, family="pi", n_jobs=-1)
    alone = fit_channels(V, X, family="pi")
    for a, b in zip(models, alone, strict=True):
        assert np.array_equal(a.weights_, b.weights_)
