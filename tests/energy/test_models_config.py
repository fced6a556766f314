"""Tests of energy.models.config: EstimatorConfig, its presets and its plain-dict form."""

import pytest

from energy import EstimatorConfig, estimator_preset
from energy.models import ESTIMATOR_PRESETS
from energy.models.config import RESAMPLE_METHODS, RUN_FEATURES
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_config_round_trips_through_plain_dict():
    for cfg in ESTIMATOR_PRESETS.values():
        assert EstimatorConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(InvalidParameterError, match="unknown EstimatorConfig field"):
        EstimatorConfig.from_dict({"colour": "red"})


def test_estimator_preset_by_name():
    assert estimator_preset("default") is ESTIMATOR_PRESETS["default"]
    paper = estimator_preset("paper")
    assert paper.name == "paper" and paper.run_features == "bins" and paper.n_spectrum_bins == 8000
    with pytest.raises(UnknownNameError, match=r"estimator preset 'fancy' is unknown; expected one of \['default', 'paper'\]"):
        estimator_preset("fancy")
    with pytest.raises(UnknownNameError, match="estimator preset"):
        estimator_preset(["default"])


def test_replace_gives_a_new_validated_config():
    base = estimator_preset("default")
    small = base.replace(hidden_sizes=(8,), n_members=2)
    assert small.hidden_sizes == (8,) and small.n_members == 2 and base.hidden_sizes != (8,)
    assert small.replace() == small
    with pytest.raises(InvalidParameterError, match="hidden_sizes"):
        base.replace(hidden_sizes=())


def test_named_choices():
    assert RUN_FEATURES == ("bins", "bands", "none") and RESAMPLE_METHODS == ("linear", "previous")
    with pytest.raises(UnknownNameError, match="resample_method"):
        EstimatorConfig(resample_method="cubic")
