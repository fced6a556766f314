"""Tests of energy.models.kinds: a new unfitted current model by kind name."""

import pytest

from energy.models import (
    CURRENT_MODEL_KINDS,
    ConstantCurrentModel,
    LinearCurrentModel,
    PhysicsCurrentModel,
    VibrationCurrentEstimator,
    new_current_model,
)
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_each_baseline_kind_gives_its_unfitted_class():
    assert CURRENT_MODEL_KINDS == ("estimator", "paper", "linear", "physics", "constant")
    for kind, cls in (("linear", LinearCurrentModel), ("physics", PhysicsCurrentModel), ("constant", ConstantCurrentModel)):
        model = new_current_model(kind)
        assert type(model) is cls and not model.is_fitted


def test_learned_kinds_are_estimators_of_their_preset():
    est = new_current_model("estimator", seed=3, n_threads=1)
    assert isinstance(est, VibrationCurrentEstimator) and not est.is_fitted
    assert est.get_params()["config"] == "default" and est.get_params()["seed"] == 3
    paper = new_current_model("paper")
    assert paper.get_params()["config"] == "paper"
    banded = new_current_model("estimator", band_hz=(2.0, 30.0))
    assert banded.get_params()["config"].band_hz == (2.0, 30.0)


def test_unknown_kinds_and_a_band_for_a_baseline_are_refused():
    with pytest.raises(UnknownNameError, match=r"kind must be one of \['estimator', 'paper', 'linear', 'physics', "
                                               r"'constant'\], got 'forest'"):
        new_current_model("forest")
    with pytest.raises(InvalidParameterError, match="band_hz applies to the estimator and paper models only, got kind 'linear'"):
        new_current_model("linear", band_hz=(1.0, 10.0))
