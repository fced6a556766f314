"""benchmarks/forecast_grounds.py: the grounds it draws are seeded, apart from the presets and labelled run by run."""

from __future__ import annotations

import forecast_grounds  # benchmarks/ is on sys.path: tests/conftest.py
import numpy as np


def test_grounds_are_seeded_within_their_ranges_and_differ():
    fg = forecast_grounds
    a, b = fg.draw_grounds(5, seed=3), fg.draw_grounds(5, seed=3)
    assert a == b and a != fg.draw_grounds(5, seed=4)
    for fx in a.values():
        for name, (lo, hi) in fg.GROUND_RANGES.items():
            assert lo <= getattr(fx, name) <= hi
    assert len({fx.payload_kg for fx in a.values()}) == 5


def test_each_run_carries_its_ground_and_runs_differ():
    fg = forecast_grounds
    grounds = fg.draw_grounds(2, seed=0)
    logs = fg.ground_logs(grounds, runs=2, seed=0)
    assert [lg.meta.ground_label for lg in logs] == ["g0", "g0", "g1", "g1"]
    assert len({lg.meta.source for lg in logs}) == 4
    assert not np.array_equal(logs[0].current_left_a[:50], logs[1].current_left_a[:50])
