"""Tests of planner.model_cost: a saved current model as edge costs, checked against the robot and the map's grounds."""

import numpy as np
import pytest

from energy import load_current_model, robot_preset
from planner.model_cost import (
    ModelCompatibilityWarning,
    model_energy_cost,
    model_energy_model,
    model_grounds,
    robot_matches,
)
from terrain import DataError, InvalidParameterError, TerrainMap, UnknownNameError

HUSKY = robot_preset("husky")


def _no_classes_map():
    return TerrainMap(np.zeros((6, 8)), 1.0)


def test_robot_names_match_when_the_preset_name_is_in_the_log_name():
    assert robot_matches("husky", "husky") and robot_matches("husky", "Clearpath_Husky_A200")
    assert not robot_matches("husky", "jackal") and not robot_matches("jackal", "unknown")


def test_each_ground_class_gets_its_own_model_id_fed_its_recorded_vibration(corridor_map, known_model):
    lem, plan = model_energy_model(corridor_map, known_model(), HUSKY)
    assert plan.by_class == {0: "loam", 1: "gravel"}  # the map's "Loam" matched case-insensitively
    cost = lem.energy_cost(corridor_map, 0.5)
    assert cost.tables.ground_labels == ("loam", "gravel")
    mid = cost.tables.grade_table_j_per_m.shape[1] // 2
    loam, gravel = cost.tables.grade_table_j_per_m[:, mid]
    assert loam < gravel  # 2 A vs 2.5 A per side: each id saw its own ground's vibration
    rows = np.asarray(cost.ground_rows)
    assert np.all(rows[np.asarray(corridor_map.ground) == 0] == 0) and np.all(rows[np.asarray(corridor_map.ground) == 1] == 1)


def test_a_saved_and_loaded_model_prices_the_map_like_the_fitted_one(tmp_path, corridor_map, known_model):
    model = known_model()
    path = model.save(tmp_path / "model.tw")
    loaded = load_current_model(path)
    a = model_energy_cost(corridor_map, model, HUSKY, 0.5)
    b = model_energy_cost(corridor_map, loaded, HUSKY, 0.5)
    assert np.array_equal(a.tables.grade_table_j_per_m, b.tables.grade_table_j_per_m)
    assert np.array_equal(a.tables.grade_sd_table_j_per_m, b.tables.grade_sd_table_j_per_m)


def test_a_model_of_another_robot_is_refused_naming_both(corridor_map, known_model):
    with pytest.raises(InvalidParameterError, match=r"trained on robot\(s\) \['jackal_1'\], not on the robot preset "
                       r"'husky'.* or give the model's robot as `robot`$") as raised:
        model_energy_cost(corridor_map, known_model(robot="jackal_1"), HUSKY, 0.5)
    assert raised.value.parameter == "robot"  # the command line says --robot


def test_an_unnamed_robot_is_a_warning_not_a_refusal(corridor_map, known_model):
    with pytest.warns(ModelCompatibilityWarning, match="do not name their robot"):
        cost = model_energy_cost(corridor_map, known_model(robot="unknown"), HUSKY, 0.5)
    assert cost.tables.ground_labels == ("loam", "gravel")


def test_a_map_ground_the_model_never_drove_is_refused_listing_both(corridor_map, known_model):
    with pytest.raises(UnknownNameError, match=r"never drove the map's ground\(s\) \['gravel'\].*trained on grounds "
                                               r"\['loam'\]; the map has \['Loam', 'gravel'\].*model_ground") as err:
        model_energy_cost(corridor_map, known_model(trained_on=("loam",)), HUSKY, 0.5)
    assert err.value.parameter == "model_ground"


def test_model_ground_prices_every_cell_as_one_training_ground(corridor_map, known_model):
    cost = model_energy_cost(corridor_map, known_model(), HUSKY, 0.5, model_ground="GRAVEL")
    assert cost.tables.ground_labels == ("gravel",) and not cost.has_interval  # gravel has no spread
    with pytest.raises(UnknownNameError, match="model_ground 'sand' is not a ground the model drove"):
        model_energy_cost(corridor_map, known_model(), HUSKY, 0.5, model_ground="sand")


def test_a_map_without_ground_classes(known_model):
    tmap = _no_classes_map()
    one = model_energy_cost(tmap, known_model(trained_on=("loam",)), HUSKY, 0.5)  # one training ground: used directly
    assert one.tables.ground_labels == ("loam",) and one.has_interval
    with pytest.raises(InvalidParameterError, match="unknown ground.*model_ground NAME"):
        model_energy_cost(tmap, known_model(), HUSKY, 0.5)
    assert model_grounds(tmap, known_model().training_summary, model_ground="loam").by_class == {-1: "loam"}


def test_a_vibration_conditioned_model_without_the_grounds_recording_is_refused(corridor_map, known_model):
    with pytest.raises(DataError, match="no recorded vibration of ground 'loam'"):
        model_energy_cost(corridor_map, known_model(recorded=["gravel"]), HUSKY, 0.5)


def test_a_model_without_an_interval_gives_a_cost_without_spread_tables(corridor_map, known_model):
    flat = {"loam": [9.0, 2.0, 4.0, 0.0], "gravel": [10.5, 2.5, 4.5, 0.0]}
    cost = model_energy_cost(corridor_map, known_model(grounds=flat), HUSKY, 0.5)
    assert cost.tables.grade_sd_table_j_per_m is None and not cost.has_interval


def test_a_class_the_model_never_drove_can_be_priced_as_one_it_did(corridor_map, known_model):
    model = known_model(trained_on=("loam",))  # never drove the map's gravel corridor
    with pytest.raises(UnknownNameError, match="CLASS=NAME"):
        model_grounds(corridor_map, model.training_summary)
    plan = model_grounds(corridor_map, model.training_summary, model_ground={"Gravel": "loam"})
    assert plan.by_class == {0: "loam", 1: "loam"}
    with pytest.raises(UnknownNameError, match="does not have"):
        model_grounds(corridor_map, model.training_summary, model_ground={"sand": "loam"})
    with pytest.raises(UnknownNameError, match="never drove"):
        model_grounds(corridor_map, model.training_summary, model_ground={"gravel": "snow"})


def test_model_ground_tokens_parse_into_a_name_or_a_mapping():
    from planner.model_cost import parse_model_ground

    assert parse_model_ground(["snow"]) == "snow"
    assert parse_model_ground(["grass=asphalt", "sand=snow"]) == {"grass": "asphalt", "sand": "snow"}
    for bad in (["grass="], ["a=b", "a=c"], ["x", "y"]):
        with pytest.raises(InvalidParameterError):
            parse_model_ground(bad)


def test_parse_model_ground_names_the_setting_as_asked():
    from planner.model_cost import parse_model_ground

    assert parse_model_ground("snow") == "snow"
    with pytest.raises(InvalidParameterError, match="--model-ground names map class 'a' twice"):
        parse_model_ground(["a=b", "a=c"], "--model-ground")
    with pytest.raises(InvalidParameterError, match="model_ground takes one NAME or CLASS=NAME pairs"):
        parse_model_ground([])
