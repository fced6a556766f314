"""energy.energy_model: the one seam planning knows — any object with the two methods is an energy model."""

from __future__ import annotations

import numpy as np
import pytest

from energy import EnergyModel, IntervalEnergyModel, PhysicsEnergyModel, ground_preset, robot_preset
from planner import CostSpec, LearnedEnergyModel
from planner.registry import CellModelRegistry
from terrain import InvalidParameterError, flat_map


class FlatRate:
    """A user's own model: 10 J per metre on every grade and cell class, 2 J per radian of turn."""

    def energy_per_metre_j(self, speed_mps, grade, cell_class, /):
        return np.full(np.shape(grade), 10.0)

    def turn_energy_j(self, heading_change_rad, cell_class, /):
        return 2.0 * np.abs(np.asarray(heading_change_rad, dtype=float))


def test_the_library_models_are_energy_models():
    assert isinstance(PhysicsEnergyModel(robot_preset("husky")), EnergyModel)
    assert not isinstance(PhysicsEnergyModel(robot_preset("husky")), IntervalEnergyModel)  # no spreads
    assert isinstance(FlatRate(), EnergyModel) and not isinstance(object(), EnergyModel)


def test_a_learned_energy_model_is_one_with_an_interval(known_model):
    tmap = flat_map((10, 12), 1.0, ground="loam")
    model = known_model(trained_on=("loam",))
    registry = CellModelRegistry.from_terrain(tmap, model, prior_name="prior")
    learned = LearnedEnergyModel(registry, robot_preset("husky"), ground_preset("asphalt"))
    assert isinstance(learned, IntervalEnergyModel)
    model_id = int(registry.model_ids_in_use()[0])
    assert learned.energy_per_metre_j(0.5, [0.0, 0.1], model_id).shape == (2,)


def test_an_edge_cost_prices_any_energy_model_and_refuses_what_is_not_one():
    tmap = flat_map((10, 20), 1.0, ground="asphalt")
    cost = CostSpec(energy_model=FlatRate(), grounds={"asphalt": None}, speed_mps=0.5).build(tmap)
    # 12 m straight on level ground: 10 J/m
    assert cost.segment_energy_j([[2.5, 5.5]], [[14.5, 5.5]])[0] == pytest.approx(120.0)
    with pytest.raises(InvalidParameterError, match=r"energy_model must be an energy.EnergyModel .* got 'str'"):
        CostSpec(energy_model="physics", grounds={"asphalt": None}, speed_mps=0.5)
