"""Tests of energy.diagnosis.plots_gap: the residual over time, and the helpers of the gap figures (no diagnosis needed)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from energy.diagnosis.plots_gap import REGIME_PANELS, checked_diagnosis, log_list, plot_residual_time
from terrain import InvalidParameterError

PNG = b"\x89PNG\r\n\x1a\n"


def _runs(n_runs: int = 3) -> tuple[list[InteractionLog], list[np.ndarray]]:
    logs, preds = [], []
    for k in range(n_runs):
        t = np.arange(0.0, 20.0, 0.1)
        cur = np.full(t.size, 2.0 + 0.5 * k)  # run k: the model predicts 0.5 k A too little
        logs.append(InteractionLog(t, np.full(t.size, 0.4), np.zeros(t.size), cur, cur, t, np.full(t.size, 9.81),
                                   meta=LogMeta(source=f"run{k}.csv", ground_label="sand")))
        preds.append(np.full((t.size, 2), 2.0))
    return logs, preds


def test_the_residual_figure_is_written(tmp_path):
    logs, preds = _runs()
    path = plot_residual_time(logs, preds, tmp_path / "res.png")
    assert path == tmp_path / "res.png" and path.read_bytes()[:8] == PNG


def test_it_draws_the_runs_of_largest_gap_into_the_callers_axes(tmp_path):
    logs, preds = _runs()
    fig, axes = plt.subplots(2, 1)
    try:
        out = plot_residual_time(logs, preds, ax=list(axes), max_runs=2)
        assert tuple(out) == tuple(axes)
        assert axes[0].get_title(loc="left").startswith("run 1: run1.csv, sand") and axes[1].get_title(loc="left").startswith("run 2")
        chosen = plot_residual_time(logs, preds, ax=[axes[0]], runs=[0])
        assert chosen[0] is axes[0]
    finally:
        plt.close(fig)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(runs=[]), "runs must be None or a non-empty sequence of run indices"),
    (dict(runs=[0, 0]), r"runs has duplicates: \[0, 0\]"),
    (dict(runs=[5]), r"runs\[0\]"),
    (dict(runs=[0, 1, 2], max_runs=2), "runs names 3 runs; at most max_runs = 2 are drawn"),
    (dict(max_runs=9), "max_runs"),
    (dict(section_s=0.0), "section_s"),
])
def test_bad_runs_and_numbers_are_refused(tmp_path, kwargs, match):
    logs, preds = _runs()
    with pytest.raises(InvalidParameterError, match=match):
        plot_residual_time(logs, preds, tmp_path / "res.png", **kwargs)
    assert not (tmp_path / "res.png").exists()


def test_log_list_and_checked_diagnosis():
    logs, _ = _runs(1)
    assert log_list(logs[0]) == logs and log_list(tuple(logs)) == logs
    with pytest.raises(InvalidParameterError, match="logs must be an InteractionLog or a sequence of them, got 'str'"):
        log_list("run.csv")
    with pytest.raises(InvalidParameterError, match="diagnosis must be a Diagnosis, got 'dict'"):
        checked_diagnosis({})
    assert REGIME_PANELS == ("speed", "turning", "acceleration", "grade", "ground", "side")
