"""Tests of planner.missions.monte_carlo_report: monte_carlo_mission, a MonteCarloResult with its route and header."""

from __future__ import annotations

import json

import pytest

import terrain
from energy import Battery
from planner.cost_spec import CostSpec
from planner.missions import MonteCarloResult, MonteCarloStudy
from planner.missions.monte_carlo_report import monte_carlo_mission
from terrain import FigureWarning, InvalidParameterError, TerrainMap

START, GOAL = (3.0, 12.0), (37.0, 12.0)


@pytest.fixture(scope="module")
def wall() -> TerrainMap:
    return terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(10, 14))


@pytest.fixture(scope="module")
def report(wall) -> MonteCarloResult:
    return monte_carlo_mission(wall, START, GOAL, MonteCarloStudy(4, seed=3), battery=Battery(5.0, 24.0), map_label="wall")


def test_the_lattice_route_is_driven_n_times(report):
    assert report.route.status == "exact" and report.route.planner.startswith("lattice")
    assert isinstance(report, MonteCarloResult) and report.n == 4
    assert report.where == "in process" and report.ok and report.fits and report.risk_need_j is None


def test_the_summary_gives_battery_route_and_study(report):
    lines = report.summary().splitlines()
    assert lines[0] == "map: wall; robot husky; battery 5 Ah at 24 V, reserve 20 %"
    assert lines[1] == f"route: {report.route.length_m:.1f} m, planned {report.route.energy_wh:.2f} Wh; 4 missions"
    assert "\n".join(lines[2:]) == report.study_summary()


def test_the_files(report, tmp_path):
    written = report.write(tmp_path)
    assert [p.name for p in written] == ["monte_carlo.json", "monte_carlo.csv", "monte_carlo.png"]
    assert json.loads((tmp_path / "monte_carlo.json").read_text())["n"] == 4


def test_a_figure_that_fails_warns(report, tmp_path, monkeypatch):
    monkeypatch.setattr(MonteCarloResult, "plot", lambda *a, **k: 1 / 0)
    with pytest.warns(FigureWarning, match="monte_carlo.png: ZeroDivisionError"):
        assert len(report.write(tmp_path)) == 2


def test_too_small_a_risk_budget_is_not_ok(wall):
    tiny = monte_carlo_mission(wall, START, GOAL, MonteCarloStudy(3, seed=0, max_risk_pct=0.0),
                               battery=Battery(0.01, 24.0))
    assert tiny.p_below_reserve > 0 and not tiny.ok


def test_no_route_drives_nothing(tmp_path):
    closed = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(0, 0))
    report = monte_carlo_mission(closed, START, GOAL, MonteCarloStudy(3), battery=Battery(5.0, 24.0))
    assert report.n == 0 and not report.route.found and not report.ok and report.write(tmp_path) == []
    assert report.summary().splitlines()[-1] == "no route from (3.0, 12.0) to (37.0, 12.0): status 'infeasible'"


def test_the_model_quantile_is_checked_against_the_usable_battery(corridor_map, known_model):
    sandy = TerrainMap(corridor_map.elevation_m, 1.0, ground=corridor_map.ground, obstacle=corridor_map.obstacle,
                       ground_names={0: "sand", 1: "gravel"})
    grounds = {"sand": [9.0, 2.0, 4.0, 1.0], "gravel": [10.5, 2.5, 4.5, 0.0]}
    model = known_model(trained_on=("sand", "gravel"), grounds=grounds)
    kw = dict(pricing=CostSpec(model=model, risk=0.9))
    big = monte_carlo_mission(sandy, (2.5, 7.5), (27.5, 7.5), MonteCarloStudy(20, seed=0, draw_from="model"), battery=Battery(5.0, 24.0), **kw)
    assert big.fits and big.ok and big.risk_need_j == big.forecast.quantile_j(0.9)
    assert "reserve check at Q = 0.9: the route's 0.9 quantile" in big.summary() and "fits" in big.summary()
    small = monte_carlo_mission(sandy, (2.5, 7.5), (27.5, 7.5), MonteCarloStudy(20, seed=0, draw_from="model"), battery=Battery(0.01, 24.0), **kw)
    assert not small.fits and not small.ok and "does NOT fit" in small.summary()


def test_risk_needs_a_model_with_an_interval(wall):
    with pytest.raises(InvalidParameterError, match="risk and draw_from model need a model with a predictive "
                                                    "interval; the physics model gives none"):
        monte_carlo_mission(wall, START, GOAL, MonteCarloStudy(2), battery=Battery(5.0, 24.0), pricing=CostSpec(risk=0.9))
    with pytest.raises(InvalidParameterError, match="max_risk_pct"):
        monte_carlo_mission(wall, START, GOAL, MonteCarloStudy(2, max_risk_pct=101.0), battery=Battery(5.0, 24.0))
