"""Tests of energy.diagnosis.result: EffectScore, WaterfallStep and Diagnosis (frozen, its JSON and its one-page report)."""

import dataclasses
import json
import math

import numpy as np
import pytest
from turning_samples import turning_diagnosis

from energy import InteractionLog
from energy.diagnosis import localise_gap
from energy.diagnosis.result import DIAGNOSIS_FORMAT_VERSION, MARKDOWN_SLICES, EffectScore, WaterfallStep
from terrawatt_base.formats import read_result_json


@pytest.fixture(scope="module")
def turning():
    return turning_diagnosis()


def test_result_serialises(turning, tmp_path):
    _, _, d = turning
    p = d.write_json(tmp_path / "diagnosis.json")
    assert p.exists() and "ranking" in p.read_text()
    doc = read_result_json(p, "diagnosis", DIAGNOSIS_FORMAT_VERSION)  # through the one result codec
    assert (doc["format"], doc["format_version"]) == ("terrawatt-diagnosis", 1) and doc["chosen"] == list(d.chosen)
    md = d.to_markdown()
    assert "Waterfall" in md and "turning_resistance" in md
    with pytest.raises(dataclasses.FrozenInstanceError):
        d.chosen = ()


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
    assert len(table) == 10
    assert len(md.splitlines()) < 60
    doc = json.loads(big.write_json(tmp_path / "diagnosis.json").read_text())
    assert len(doc["localisation"]) == len(rows)
    assert {"gap_mah", "gap_pct", "measured_mah", "gap_interval_mah", "share_pct"} <= set(doc["localisation"][0])


def _score(**changes) -> EffectScore:
    base = dict(name="mass", kind="parameter", parameters={"mass_scale": 1.8}, shrink_pct=40.0,
                shrink_interval_pct=(30.0, 50.0), n_parameters=1, priors={"mass_scale": 1.0},
                plausible={"mass_scale": (0.5, 2.5)})
    base.update(changes)
    return EffectScore(**base)


def test_an_effect_score_in_plain_words_and_as_json():
    s = _score()
    assert s.parameter_text() == "mass_scale = 1.8 (prior 1; plausible 0.5 … 2.5)"
    assert not s.doubtful and _score(flags=("pinned",)).doubtful
    d = json.loads(json.dumps(s.to_dict(), allow_nan=True))
    assert d["shrink_interval_pct"] == [30.0, 50.0] and d["plausible"] == {"mass_scale": [0.5, 2.5]}
    assert d["doubtful"] is False and d["flags"] == [] and math.isnan(d["added_pct"])
    assert _score(priors={}, plausible={}).parameter_text() == "mass_scale = 1.8"


def test_a_waterfall_step_as_json():
    w = WaterfallStep("+ mass", 2.5, 4.0, 0.3, 60.0)
    assert w.to_dict() == {"label": "+ mass", "charge_error_pct": 2.5, "section_error_pct": 4.0, "rmse_a": 0.3,
                           "shrink_pct": 60.0}
    assert MARKDOWN_SLICES == 10  # the report's "where the gap lies" table, as the one-page test counts
