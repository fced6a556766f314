"""CorrectedCurrentModel: composes the chosen effects, refits them, saves and loads through the model file format."""

import dataclasses

import numpy as np
import pytest

from energy import LinearCurrentModel, PhysicsCurrentModel, load_current_model
from terrawatt_base.errors import InvalidParameterError
from energy.diagnosis import CorrectedCurrentModel
from diagnosis_scenarios import scenario


@pytest.fixture(scope="module")
def setup():
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=2, run_duration_s=6.0)
    return sc.make_logs(3), sc.make_model(3)


def test_fit_recovers_the_withheld_term_and_roundtrips(setup, tmp_path):
    logs, model = setup
    cm = CorrectedCurrentModel(model, ["turning_resistance", "current_gain"]).fit(logs)
    params = cm.fitted_parameters()
    assert abs(params["turning_resistance"]["gain"] - 1.0) < 0.2
    pred = cm.predict(logs[0])
    assert pred.shape == (len(logs[0]), 2) and np.all(pred >= 0)  # the base clamps at 0, so does the correction
    path = cm.save(tmp_path / "corrected.zip")
    back = CorrectedCurrentModel.load(path)
    assert isinstance(back.base, PhysicsCurrentModel)
    np.testing.assert_allclose(back.predict(logs[1]), cm.predict(logs[1]))
    any_model = load_current_model(path)  # the generic loader knows the class too
    assert isinstance(any_model, CorrectedCurrentModel)
    np.testing.assert_allclose(any_model.predict(logs[1]), cm.predict(logs[1]))


def test_no_effects_is_the_base(setup):
    logs, model = setup
    cm = CorrectedCurrentModel(model, []).fit(logs)
    np.testing.assert_allclose(cm.predict(logs[0]), model.predict(logs[0]))


def test_bad_parameters(setup):
    logs, _ = setup
    with pytest.raises(InvalidParameterError, match="fitted CurrentModel"):
        CorrectedCurrentModel(LinearCurrentModel(), ["current_gain"]).fit(logs)
    with pytest.raises(InvalidParameterError, match="sequence of effect names"):
        CorrectedCurrentModel(LinearCurrentModel().fit(logs), "current_gain").fit(logs)
