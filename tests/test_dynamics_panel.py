"""The pair on the whole dynamics panel (slow): identified as a user would, it tracks as the
pair built on each stage's true linear part does, and far better than its hysteresis model
alone at 100 and 200 Hz (benchmarks/bench_dynamics_panel.py, docs/dynamics.md)."""

from __future__ import annotations

import pytest
from benchmarks.bench_dynamics_panel import WITH, identify_pair, identify_true, panel_table
from benchmarks.dynamics_panel import DYNAMICS_STAGES


@pytest.mark.slow
def test_the_pair_tracks_at_its_bound_on_every_tuning_stage():
    found = panel_table(DYNAMICS_STAGES, identify_pair)
    bound = panel_table(DYNAMICS_STAGES, identify_true)
    for name, cells in found.items():
        for model in ("MPI", "Preisach"):
            alone, pair = cells[model], cells[model + WITH]
            true = bound[name][model + WITH]
            for ref in ("1 Hz", "10 Hz", "100 Hz", "200 Hz"):
                # the identification leaves nothing that the true linear part would not
                assert pair[ref] <= true[ref] + 0.03, (name, model, ref)
            assert pair["100 Hz"] <= 0.5 * alone["100 Hz"], (name, model)
            assert pair["200 Hz"] <= 0.4 * alone["200 Hz"], (name, model)
            # slow tracking: no worse than 1.25x alone (the Preisach model on the Bouc-Wen
            # stage with log-uniform creep excepted, at 1.83x, as its bound)
            if (name, model) != ("boucwen630", "Preisach"):
                assert pair["1 Hz"] <= 1.25 * alone["1 Hz"], (name, model)
