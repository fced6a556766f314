"""CorrectedCurrentModel: composes the chosen effects, refits them, saves and loads through the model file format."""

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import scenario

from energy import LinearCurrentModel, PhysicsCurrentModel, load_current_model
from energy.diagnosis import CorrectedCurrentModel
from terrawatt_base.errors import InvalidParameterError


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


def test_a_base_on_a_map_needs_its_map_again_after_loading(setup, tmp_path):
    # the scenario's runs carry poses on its map: a physics base that drives the map's slope, corrected, saved,
    # loaded: it refuses to predict on level ground until given the map, then predicts as before
    from terrawatt_base.errors import DataError

    logs, model = setup
    tmap = dataclasses.replace(scenario("turning_resistance"), n_runs=2, run_duration_s=6.0).terrain
    base = PhysicsCurrentModel(model.robot, model.ground, fit_parameters=(), effects=model.effects,
                               terrain=tmap).fit(logs)
    cm = CorrectedCurrentModel(base, ["turning_resistance"]).fit(logs)
    back = load_current_model(cm.save(tmp_path / "on_map.zip"))
    with pytest.raises(DataError, match="with_terrain"):
        back.predict(logs[0])
    np.testing.assert_allclose(back.with_terrain(tmap).predict(logs[0]), cm.predict(logs[0]))
