"""Tests of energy.diagnosis.report: the Diagnosis answer (frozen), printed (summary), saved (JSON, one-page
markdown, every file) and a failing figure; diagnosed from a ModelUnderDiagnosis."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest
from diagnosis_scenarios import scenario
from turning_samples import turning_diagnosis

from energy import InteractionLog, load_current_model
from energy.diagnosis import (
    DIAGNOSIS_FILES,
    Diagnosis,
    FitSettings,
    diagnose,
    localise_gap,
    model_under_diagnosis,
)
from energy.diagnosis.report import DIAGNOSIS_FORMAT_VERSION, MARKDOWN_SLICES
from terrawatt_base import plot_target
from terrawatt_base.errors import FigureWarning, InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_result_json, write_result_json


@pytest.fixture(scope="module")
def case():
    """The turning case: a physics model without turning resistance, diagnosed on 3 short runs on its map."""
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    logs, tmap = sc.make_logs(0), sc.terrain
    src = model_under_diagnosis("physics", logs, ground="coated_wood", without=["turning_resistance"])
    d = diagnose(src, logs, terrain=tmap, effects=["turning_resistance", "idle_current"], settings=FitSettings(seed=1))
    return src, d, logs, tmap


@pytest.fixture(scope="module")
def turning():
    return turning_diagnosis()


def test_the_answer_carries_where_its_model_comes_from_and_what_it_ran_on(case):
    src, d, logs, tmap = case
    assert isinstance(d, Diagnosis) and d.logs == tuple(logs) and d.terrain is tmap
    assert d.model_note == src.note and "presets as given" in src.note
    assert d.current.waterfall[0].label == "as given" and d.settings == FitSettings(seed=1)
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.verdict = ()


def test_the_summary_is_the_verdict_then_the_waterfall(case):
    _, d, _, _ = case
    text = d.summary()
    assert text.startswith(d.verdict[0])
    table = d.current.table()
    assert table in text and "charge err %" in table and "RMSE A" in table
    assert len(table.splitlines()) == 1 + len(d.current.waterfall)
    assert d.power is None and "battery power" not in text  # no battery power in these logs
    assert "skipped" not in text  # logs with poses and a map: every figure has its data
    bare = dataclasses.replace(d, terrain=None)
    assert "skipped gap_map.png: " in bare.summary()


def test_the_json_goes_through_the_one_result_codec(turning, tmp_path):
    _, _, d = turning
    p = write_result_json(tmp_path / "diagnosis.json", d.to_dict())  # as write writes it
    doc = read_result_json(p, "diagnosis", DIAGNOSIS_FORMAT_VERSION)
    assert (doc["format"], doc["format_version"]) == ("terrawatt-diagnosis", 1)
    assert doc["chosen"] == list(d.current.chosen) and doc["split"] == d.settings.split
    assert list(doc["before"]) == ["measured_mah", "predicted_mah", "gap_mah", "charge_error_pct",
                                   "section_error_pct", "rmse_a", "n_runs", "n_samples", "duration_s"]
    md = d.to_markdown()
    assert "Waterfall" in md and "turning_resistance" in md and "| step | charge error |" in md


def test_the_report_is_one_page_and_the_json_keeps_every_slice(turning, tmp_path):
    _, _, d = turning
    t = np.arange(0.0, 600.0, 0.1)  # two 10-minute runs: 150 time sections of 8 s
    v = 0.5 + 0.4 * np.sin(t / 7.0)
    w = 0.6 * np.sin(t / 5.0)
    logs = [InteractionLog(t, v, w, 1.0 + np.abs(w) + k, 1.0 + np.abs(w), t, np.full(t.size, 9.81)) for k in (0, 1)]
    rows = localise_gap(logs, [np.ones((t.size, 2)), np.ones((t.size, 2))])
    assert sum(r.dimension == "time" for r in rows) == 150
    big = dataclasses.replace(d, localisation=rows)
    md = big.to_markdown()
    where = md.split("## Where the gap lies")[1].split("##")[0]
    table = [line for line in where.splitlines() if line.startswith("| ") and not line.startswith("| dimension")]
    assert len(table) == MARKDOWN_SLICES == 10
    assert len(md.splitlines()) < 60
    doc = json.loads(write_result_json(tmp_path / "diagnosis.json", big.to_dict()).read_text())
    assert len(doc["localisation"]) == len(rows)
    assert {"gap_mah", "gap_pct", "measured_mah", "gap_interval_mah", "share_pct"} <= set(doc["localisation"][0])


def test_plot_draws_the_effect_ranking(turning, tmp_path):
    from matplotlib.figure import Figure

    _, _, d = turning
    ax = Figure().subplots()
    assert d.plot(ax=ax, max_effects=2) is ax
    assert len(ax.patches) >= 2 and ax.patches[0].get_width() > 0
    png = d.plot(tmp_path / "ranking.png")
    assert png == tmp_path / "ranking.png" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(InvalidParameterError, match="got neither"):
        d.plot()


def test_write_writes_every_file(case, tmp_path):
    _, d, _, _ = case
    written = d.write(tmp_path / "out")
    assert sorted(p.name for p in written) == sorted(DIAGNOSIS_FILES)
    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text())
    assert doc["model_note"] == d.model_note
    assert type(load_current_model(tmp_path / "out" / "corrected_model.zip")).__name__ == "CorrectedCurrentModel"


def test_a_failing_figure_warns_naming_its_file_or_raises(case, tmp_path, monkeypatch):
    _, d, _, _ = case

    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plot_target, "new_figure", broken)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        written = d.write(tmp_path / "a")
    assert [p.name for p in written] == ["diagnosis.json", "diagnosis.md", "corrected_model.zip"]
    messages = [str(w.message) for w in caught if issubclass(w.category, FigureWarning)]
    assert len(messages) == len(DIAGNOSIS_FILES) - 3
    assert messages[0] == f"could not draw {tmp_path / 'a' / 'residual_time.png'}: RuntimeError: no canvas"
    with pytest.raises(RuntimeError, match="no canvas"):
        d.write(tmp_path / "b", on_figure_error="raise")
    with pytest.raises(UnknownNameError, match="on_figure_error"):
        d.write(tmp_path / "c", on_figure_error="ignore")


def test_a_model_under_diagnosis_brings_its_own_robot(case):
    src, _, logs, _ = case
    with pytest.raises(InvalidParameterError, match="robot must be None with a ModelUnderDiagnosis"):
        diagnose(src, logs, robot="husky")
    with pytest.raises(InvalidParameterError, match="settings must be a FitSettings"):
        diagnose(src, logs, settings={"seed": 1})
