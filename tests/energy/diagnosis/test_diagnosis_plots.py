"""Figures of a diagnosis: each written as a PNG, missing data skipped with its reason, bad paths refused first."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from diagnosis_scenarios import scenario

import terrain
from energy.diagnosis import FitSettings, diagnose
from energy.diagnosis.plots import (
    FIGURES,
    DiagnosisFigures,
    plot_diagnosis,
    plot_effect_ranking,
    plot_gap_by_regime,
    plot_gap_map,
    plot_residual_time,
    plot_waterfall,
    skipped_figures,
)
from terrain import DataError, FigureWarning, GridMismatchError, InvalidParameterError, UnknownNameError
from terrawatt_base import plot_target

PNG = b"\x89PNG\r\n\x1a\n"


def _png(path: Path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == PNG


@pytest.fixture(scope="module")
def case():
    """A physics model without turning resistance, diagnosed on 3 short runs with poses on a map."""
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    logs = sc.make_logs(0)
    d = diagnose(sc.make_model(0), logs, terrain=sc.terrain, settings=FitSettings(seed=0, n_bootstrap=20))
    return d, logs, sc.terrain


def _no_drawing(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("drew a figure although the path was refused")

    monkeypatch.setattr(plot_target, "new_figure", refuse)


def test_every_figure_is_written_with_no_temporary_left(case, tmp_path):
    d, logs, tmap = case
    out = plot_diagnosis(d, tmp_path / "figs")
    assert isinstance(out, DiagnosisFigures)
    assert list(out.written) == list(FIGURES) and not out.skipped and not out.failed
    assert all(_png(p) for p in out.written.values())
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == sorted(FIGURES.values())
    assert "gap_map: " in str(out)


def test_each_figure_function_returns_its_path(case, tmp_path):
    d, logs, tmap = case
    preds = [d.corrected_model.base.predict(log) for log in logs]
    preds[0] = preds[0] + 20.0  # a run the model over-predicts: its sections carry negative gaps
    paths = [
        plot_residual_time(logs, preds, tmp_path / "a.png", runs=[2, 0], section_s=4.0),
        plot_gap_by_regime(d, tmp_path / "b.png"),
        plot_gap_map(d, tmap, tmp_path / "c.png", logs=logs),
        plot_effect_ranking(d, tmp_path / "d.png", max_effects=3),
        plot_waterfall(d, tmp_path / "e.png"),
    ]
    assert paths == [tmp_path / n for n in ("a.png", "b.png", "c.png", "d.png", "e.png")]
    assert all(_png(p) for p in paths)


def test_missing_data_skips_a_figure_and_says_why(case, tmp_path):
    d, logs, tmap = case
    out = plot_diagnosis(dataclasses.replace(d, logs=(), terrain=None), tmp_path,
                         figures=["residual_time", "gap_map", "waterfall"])
    assert list(out.written) == ["waterfall"]
    assert out.skipped == {"residual_time": "no residual over time: no logs given",
                           "gap_map": "no map figure: no terrain map given (the map the runs drove on)"}
    no_poses = [dataclasses.replace(log, pose_xyh=None) for log in logs]
    out = plot_diagnosis(dataclasses.replace(d, logs=tuple(no_poses)), tmp_path / "np", figures=["gap_map"])
    assert out.written == {} and "carry no poses" in out.skipped["gap_map"]
    assert not (tmp_path / "np").exists()  # nothing to draw, no folder made
    with pytest.raises(DataError, match="no terrain map given"):
        plot_gap_map(d, None, tmp_path / "m.png")


def test_a_diagnosis_without_map_blocks_or_regimes_or_ranking_is_skipped(case, tmp_path):
    d, logs, tmap = case
    bare = dataclasses.replace(d, localisation=tuple(r for r in d.localisation if r.dimension == "time"),
                               current=dataclasses.replace(d.current, ranking=()))
    out = plot_diagnosis(bare, tmp_path)
    assert set(out.skipped) == {"gap_by_regime", "gap_map", "effect_ranking"}
    assert "no map blocks" in out.skipped["gap_map"]
    assert "no candidate effect was scored" in out.skipped["effect_ranking"]
    with pytest.raises(DataError, match="no gap by regime"):
        plot_gap_by_regime(bare, tmp_path / "r.png")
    with pytest.raises(DataError, match="no candidate effect"):
        plot_effect_ranking(bare, tmp_path / "e.png")


def test_learned_and_negative_scores_are_drawn(case, tmp_path):
    d, _, _ = case
    learned = dataclasses.replace(d.current.ranking[0], name="learned_residual", kind="learned", shrink_pct=-3.0,
                                  shrink_interval_pct=(-8.0, 1.0))
    d2 = dataclasses.replace(d, current=dataclasses.replace(d.current, ranking=(*d.current.ranking, learned),
                                                            chosen=(*d.current.chosen, "learned_residual")))
    assert _png(plot_effect_ranking(d2, tmp_path / "ranking.png"))


def test_bad_paths_are_refused_before_drawing(case, tmp_path, monkeypatch):
    d, logs, tmap = case
    preds = [d.corrected_model.base.predict(log) for log in logs]
    (tmp_path / "taken.png").mkdir()
    (tmp_path / "file").write_text("x")
    _no_drawing(monkeypatch)
    for call in (lambda p: plot_waterfall(d, p), lambda p: plot_effect_ranking(d, p),
                 lambda p: plot_gap_by_regime(d, p), lambda p: plot_gap_map(d, tmap, p),
                 lambda p: plot_residual_time(logs, preds, p)):
        with pytest.raises(InvalidParameterError, match="is a directory"):
            call(tmp_path / "taken.png")
        with pytest.raises(InvalidParameterError, match="which is a file"):
            call(tmp_path / "file" / "x.png")
    with pytest.raises(InvalidParameterError, match="is a file; expected a folder"):
        plot_diagnosis(d, tmp_path / "file")
    (tmp_path / "out" / "waterfall.png").mkdir(parents=True)
    with pytest.raises(InvalidParameterError, match="waterfall.png"):
        plot_diagnosis(d, tmp_path / "out")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["waterfall.png"]  # nothing drawn


def test_bad_arguments_are_library_errors(case, tmp_path):
    d, logs, tmap = case
    preds = [d.corrected_model.base.predict(log) for log in logs]
    with pytest.raises(InvalidParameterError, match="diagnosis must be a Diagnosis"):
        plot_waterfall({"waterfall": []}, tmp_path / "w.png")
    with pytest.raises(InvalidParameterError, match=r"runs\[0\]"):
        plot_residual_time(logs, preds, tmp_path / "r.png", runs=[7])
    with pytest.raises(InvalidParameterError, match="at most max_runs"):
        plot_residual_time(logs, preds, tmp_path / "r.png", runs=[0, 1, 2], max_runs=2)
    with pytest.raises(InvalidParameterError, match="shape"):
        plot_residual_time(logs, [p[:, :1] for p in preds], tmp_path / "r.png")
    with pytest.raises(UnknownNameError, match="figures must be one of"):
        plot_diagnosis(d, tmp_path, figures=["pie_chart"])
    with pytest.raises(UnknownNameError, match="on_error"):
        plot_diagnosis(d, tmp_path, on_error="ignore")
    small = terrain.flat_map((10, 10), 1.0)
    with pytest.raises(GridMismatchError, match="the map the diagnosis ran on"):
        plot_gap_map(d, small, tmp_path / "m.png")


def test_a_failing_figure_warns_when_asked_and_raises_otherwise(case, tmp_path, monkeypatch):
    d, logs, _ = case

    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plot_target, "new_figure", broken)
    with pytest.raises(RuntimeError, match="no canvas"):
        plot_diagnosis(d, tmp_path, figures=["waterfall"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = plot_diagnosis(d, tmp_path, figures=["waterfall", "gap_by_regime"], on_error="warn")
    assert out.written == {} and set(out.failed) == {"waterfall", "gap_by_regime"}
    assert "RuntimeError: no canvas" in out.failed["waterfall"]
    assert sum(issubclass(w.category, FigureWarning) for w in caught) == 2
    assert np.isfinite(d.current.before.rmse)  # the diagnosis is untouched


# ----------------------------------------------------------------- drawn into the caller's axes
def test_each_figure_draws_into_the_callers_axes_and_writes_nothing(case, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from energy.diagnosis.plots_gap import regime_rows

    d, logs, tmap = case
    preds = [d.corrected_model.base.predict(log) for log in logs]
    monkeypatch.chdir(tmp_path)
    open_before = plt.get_fignums()
    fig = Figure()
    ax_map, ax_rank = fig.subplots(1, 2)
    assert plot_gap_map(d, tmap, ax=ax_map, logs=logs) is ax_map
    assert len(ax_map.images) == 2 and len(fig.axes) == 3  # hillshade and gap, the colour bar beside ax_map
    assert ax_map.get_title().startswith("gap on the map")
    assert plot_effect_ranking(d, ax=ax_rank, max_effects=3) is ax_rank
    assert len(ax_rank.patches) == 3 and ax_rank.get_title().startswith("candidate effects")

    water = Figure().subplots(1, 3)
    assert plot_waterfall(d, ax=water) == tuple(water)
    assert [a.get_title() for a in water] == ["whole-set charge error (%)", "8 s section error (%)", "RMSE (A)"]
    assert all(len(a.patches) == len(d.current.waterfall) for a in water)
    assert water[0].figure.get_suptitle() == ""  # the suptitle belongs to a figure the function makes

    runs = Figure().subplots(2, 1)
    assert plot_residual_time(logs, preds, ax=runs, runs=[2, 0], section_s=4.0) == tuple(runs)
    assert [a.get_title(loc="left")[:6] for a in runs] == ["run 2:", "run 0:"]
    assert all(len(a.lines) >= 4 for a in runs)

    dims = list(regime_rows(d))  # the panels drawn: the dimensions with a known slice
    regimes = tuple(Figure().subplots(1, len(dims), squeeze=False).ravel())
    assert plot_gap_by_regime(d, ax=regimes) == regimes
    assert [a.get_title() for a in regimes] == dims and all(a.patches for a in regimes)

    assert list(tmp_path.iterdir()) == [] and plt.get_fignums() == open_before


def test_a_figure_takes_a_path_or_axes_of_its_panel_count(case, tmp_path):
    from matplotlib.figure import Figure

    d, logs, tmap = case
    preds = [d.corrected_model.base.predict(log) for log in logs]
    fig = Figure()
    one, two = fig.subplots(1, 2)
    calls = {  # one Axes for a single panel, a sequence of them for several: the keyword is ax= for both
        "one": [lambda p, **k: plot_gap_map(d, tmap, p, logs=logs, **k), lambda p, **k: plot_effect_ranking(d, p, **k)],
        "several": [lambda p, **k: plot_waterfall(d, p, **k), lambda p, **k: plot_residual_time(logs, preds, p, **k),
                    lambda p, **k: plot_gap_by_regime(d, p, **k)],
    }
    for panels, fns in calls.items():
        for call in fns:
            with pytest.raises(InvalidParameterError, match="either path .* or ax=.*got neither"):
                call(None)
            with pytest.raises(InvalidParameterError, match="either path or ax=, not both"):
                call(tmp_path / "x.png", ax=one if panels == "one" else [one])
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'Figure'"):
        plot_effect_ranking(d, ax=fig)
    with pytest.raises(InvalidParameterError, match=r"ax must hold 3 .*\(charge error, section error, RMSE\), got 2"):
        plot_waterfall(d, ax=[one, two])
    with pytest.raises(InvalidParameterError, match=r"one per run drawn: runs 0, 1, 2; choose them with runs="):
        plot_residual_time(logs, preds, ax=[one, two])
    with pytest.raises(InvalidParameterError, match=r"one per dimension: 'speed'"):
        plot_gap_by_regime(d, ax=[one])
    assert list(tmp_path.iterdir()) == [] and not one.has_data() and not two.has_data()


def test_the_skipped_figures_are_known_before_drawing(case, tmp_path):
    d, logs, tmap = case
    assert skipped_figures(d) == {}  # the logs and the map it ran on
    bare = dataclasses.replace(d, logs=(), terrain=None)
    skipped = skipped_figures(bare)
    assert list(skipped) == ["residual_time", "gap_map"] and "no logs given" in skipped["residual_time"]
    assert skipped == plot_diagnosis(bare, tmp_path, figures=["residual_time", "gap_map"]).skipped
    unranked = dataclasses.replace(d, current=dataclasses.replace(d.current, ranking=()))
    assert "no candidate effect" in skipped_figures(unranked)["effect_ranking"]
    with pytest.raises(InvalidParameterError, match="diagnosis must be a Diagnosis"):
        skipped_figures("d")
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        skipped_figures(dataclasses.replace(d, terrain="map"))
