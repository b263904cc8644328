"""Work in a forked process: the same results as done in place, or done in place."""

import sys

import numpy as np
import pytest

from hystcomp.experiment.background import BackgroundJob, draw_in_background
from hystcomp.experiment.compare import CompareConfig, twin_pairs
from hystcomp.plant import Twin, creep_twin

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork on Linux only")


def _draw(text, folder):
    (folder / "a.png").write_bytes(text.encode() * 1000)
    (folder / "b.png").write_bytes(b"b")
    return {"b.png": None, "a.png": None, "c.png": "not drawn"}


def _fail(text, folder):
    (folder / "a.png").write_bytes(b"half")
    raise ValueError(text)


def test_the_files_and_notes_come_back_as_drawn():
    job = draw_in_background(_draw, "xyz")
    assert job is not None
    notes, files = job.collect()
    assert list(notes.items()) == [("b.png", None), ("a.png", None), ("c.png", "not drawn")]
    assert files == {"a.png": b"xyz" * 1000, "b.png": b"b"}


def test_a_failure_gives_nothing_so_that_the_caller_draws():
    job = draw_in_background(_fail, "broken")
    assert job is not None
    assert job.collect() is None


def test_a_job_returns_its_result_and_none_when_it_fails():
    job = BackgroundJob.start(divmod, 17, 5)
    assert job is not None
    assert job.collect() == (3, 2)
    failed = BackgroundJob.start(divmod, 1, 0)
    assert failed is not None
    assert failed.collect() is None


def test_the_pairs_identified_in_a_second_process_are_those_identified_here(monkeypatch):
    config = CompareConfig.quick(twin=creep_twin(resonance_hz=900.0), seed=3)
    job = BackgroundJob.start(twin_pairs, config)
    assert job is not None
    record, there = job.collect()
    again, here = twin_pairs(config)
    np.testing.assert_array_equal(record.x, again.x)
    assert set(there) == set(here) == {"mpi", "preisach"}
    for method in here:
        assert there[method].dynamics.parameters() == here[method].dynamics.parameters()
        assert there[method].hysteresis.parameters() == here[method].hysteresis.parameters()
    assert there["mpi"].dynamics.resonance_hz_ == pytest.approx(900.0, rel=0.02)
    designed_here = here["mpi"].inverse().dynamics_inverse.taps
    # the inverse's design came with the pair: not designed again (no SciPy) here
    import hystcomp.models.dynamics as dynamics_module

    def refuse(*args):
        raise AssertionError("designed again")

    monkeypatch.setattr(dynamics_module, "inverse_fir", refuse)
    np.testing.assert_array_equal(there["mpi"].inverse().dynamics_inverse.taps, designed_here)
    # its noise is a stream of its own, not the twin's that measures Table I
    assert not np.array_equal(record.x, Twin(config.twin, seed=3).run(record.v))


def test_a_job_that_gives_nothing_in_time_is_ended_and_done_here():
    import time

    job = BackgroundJob.start(time.sleep, 60.0)
    assert job is not None
    start = time.perf_counter()
    assert job.collect(timeout=0.5) is None
    assert time.perf_counter() - start < 5.0
    assert not job._process.is_alive()


def test_a_cancelled_job_ends_at_once():
    import time

    job = BackgroundJob.start(time.sleep, 60.0)
    assert job is not None
    start = time.perf_counter()
    job.cancel()
    assert time.perf_counter() - start < 5.0
    assert not job._process.is_alive()


def test_an_output_folder_that_takes_no_file_is_refused_before_the_run():
    from hystcomp.errors import InvalidParameterError
    from hystcomp.experiment.report import prepare_output_dir

    with pytest.raises(InvalidParameterError, match="Cannot write into the output folder"):
        prepare_output_dir("/proc/self")
