"""The flat 30 m route, nominal battery, fixed distributions and a study runner, shared by the Monte Carlo tests."""

from __future__ import annotations

import pytest

from energy import Battery
from planner import MissionDistributions, plan_route, simulate_missions_mc
from planner.cost_spec import CostSpec
from planner.missions import MissionTruth, MonteCarloStudy

NOMINAL = Battery(2.0, 24.0)
NO_DASK = "Monte Carlo on a cluster needs the distributed extra (dask[distributed])"
FIXED = MissionDistributions(ground_coef_scale=(1.0, 1.0), payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0),
                             internal_resistance_ohm=(0.0, 0.0), speed_scale=(1.0, 1.0))


@pytest.fixture(scope="module")
def setup():
    """A 30 m route on a flat asphalt map (a few hundred samples per mission)."""
    import terrain

    tmap = terrain.flat_map((20, 40), 1.0, ground="asphalt")
    cost = CostSpec().build(tmap)
    route = plan_route(tmap, (3.5, 5.5), (33.5, 14.5), cost=cost, planner="lattice")
    assert route.found
    return tmap, route


STUDY = ("seed", "draw_from", "distributions", "chunk_size", "max_risk_pct")
TRUTH = ("robot", "grounds", "speed_mps", "current_rate_hz")


def run_mc(setup, n=6, battery=NOMINAL, **kw):
    """A study of ``n`` missions; keywords of :class:`MonteCarloStudy` and :class:`MissionTruth` go to their value."""
    tmap, route = setup
    study = MonteCarloStudy(n, **{k: kw.pop(k) for k in STUDY if k in kw})
    truth = MissionTruth(**{k: kw.pop(k) for k in TRUTH if k in kw})
    return simulate_missions_mc(tmap, route, battery, study, truth=truth, **kw)
