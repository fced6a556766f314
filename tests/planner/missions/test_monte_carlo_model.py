"""simulate_missions_mc(draw_from="model"): missions drawn from the planning model's own predictive distribution."""

import numpy as np
import pytest

from energy import Battery
from planner import CostSpec, MissionDistributions, plan_route, price_route, simulate_missions_mc
from planner.missions import MonteCarloStudy
from terrain import InvalidParameterError


@pytest.fixture
def study(corridor_map, known_model):
    cost = CostSpec(model=known_model()).build(corridor_map)
    route = plan_route(corridor_map, (2.5, 7.5), (27.5, 7.5), cost=cost, planner="lattice")  # the uncertain loam
    return corridor_map, cost, route, price_route(cost, route)


def test_model_draws_follow_the_route_interval_and_the_reserve_risk(study):
    tmap, cost, route, forecast = study
    # a battery whose energy above the 20 % reserve is the route's P90: about 10 % of missions cross it
    battery = Battery(capacity_ah=forecast.p90_j / 3600 / 24.0 / 0.8, voltage_v=24.0, min_reserve_pct=20.0)
    mc = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(2000, draw_from="model", seed=3), cost=cost)
    assert mc.draw_from == "model" and mc.ground_names == ("loam",)
    assert mc.predicted_energy_j == forecast.mean_j and mc.forecast == forecast
    assert np.mean(mc.energy_j) == pytest.approx(forecast.mean_j, abs=4 * forecast.sd_j / np.sqrt(2000))
    assert np.std(mc.energy_j) == pytest.approx(forecast.sd_j, rel=0.06)
    # one factor per ground: the energy is exactly mean + z * S_loam
    assert np.allclose(mc.energy_j, forecast.mean_j + mc.ground_scale[:, 0] * forecast.sd_by_ground_j["loam"])
    assert 0.07 < mc.p_below_reserve < 0.13
    again = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(2000, draw_from="model", seed=3), cost=cost)
    assert np.array_equal(again.energy_j, mc.energy_j)
    d = mc.to_dict(samples=False)
    assert d["draw_from"] == "model" and "distributions" not in d
    assert d["forecast_interval"]["p90_j"] == pytest.approx(forecast.p90_j)
    assert "predictive distribution" in mc.summary() and "P90" in mc.summary()


def test_model_draws_need_a_cost_with_an_interval_and_no_typed_ranges(study, flat_map):
    tmap, cost, route, _ = study
    battery = Battery(capacity_ah=5.0, voltage_v=24.0)
    with pytest.raises(InvalidParameterError, match="no cost was given"):
        simulate_missions_mc(tmap, route, battery, MonteCarloStudy(5, draw_from="model"))
    with pytest.raises(InvalidParameterError, match="takes none"):
        simulate_missions_mc(tmap, route, battery, MonteCarloStudy(5, draw_from="model", distributions=MissionDistributions()),
                             cost=cost)
    with pytest.raises(InvalidParameterError, match="draw_from must be one of"):
        simulate_missions_mc(tmap, route, battery, MonteCarloStudy(5, draw_from="ranges"), cost=cost)


def test_a_model_draw_task_that_fails_keeps_its_missions_as_error_rows(study, monkeypatch):
    from planner.missions.monte_carlo_model import ModelMissionSetup

    tmap, cost, route, forecast = study
    battery = Battery(capacity_ah=forecast.p90_j / 3600 / 24.0, voltage_v=24.0)
    whole = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(8, draw_from="model", seed=2, chunk_size=4),
                                 cost=cost)

    def dies_on_the_first(self, seqs):
        if seqs[0].spawn_key == (0,):
            raise MemoryError("out of memory")
        return [self.run(q) for q in seqs]

    monkeypatch.setattr(ModelMissionSetup, "run_chunk", dies_on_the_first)
    mc = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(8, draw_from="model", seed=2, chunk_size=4),
                              cost=cost)
    assert mc.failed.tolist() == [True] * 4 + [False] * 4 and set(mc.errors[:4]) == {"MemoryError: out of memory"}
    assert np.array_equal(mc.ground_scale, whole.ground_scale)  # the failed missions' factors, drawn from their seeds
    assert np.array_equal(mc.energy_j[4:], whole.energy_j[4:]) and np.all(np.isnan(mc.energy_j[:4]))
    assert "4 of 8 missions failed" in mc.summary()
