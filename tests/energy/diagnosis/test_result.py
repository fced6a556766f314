"""Tests of energy.diagnosis.result: an EffectScore in plain words and as JSON."""

import json
import math

from energy.diagnosis.result import EffectScore


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
