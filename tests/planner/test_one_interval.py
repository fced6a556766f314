"""One interval everywhere (issue 32): the route interval, risk-aware costs, Monte Carlo draws and the navigator's
forecast of what remains read the same predictive, a Student-t on a ground the model never drove."""

import math

import numpy as np
import pytest

from energy import Battery, InteractionLog, LinearCurrentModel, LogMeta, ground_preset, robot_preset
from energy.models import fit_interval
from energy.models.forecast import predictive_quantile
from planner import (
    AdaptiveSettings,
    CostTables,
    EnergyCost,
    LearnedEnergyModel,
    Navigator,
    RouteEnergyInterval,
    plan_route,
    price_route,
    simulate_missions_mc,
)
from planner.cost_spec import CostSpec
from planner.missions import MonteCarloStudy, NavigatorModels
from planner.plan_report import plan_and_compare
from planner.planning import RouteSearch
from planner.registry import CellModelRegistry
from terrain import InvalidParameterError, TerrainMap

GRASS_START, GRASS_GOAL = (2.5, 2.5), (37.5, 2.5)  # the bottom strip: a ground the linear model never drove
LOAM_START, LOAM_GOAL = (2.5, 8.5), (37.5, 8.5)  # the top strip: the known model's loam, a Gaussian forecast


def _run(seed, ground, offset_a):
    """A 30 s run of known currents ``0.5 + 4 v + turning + offset`` (0.1 A noise) on ``ground``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0, 0.1)
    v = 0.45 + 0.35 * np.sin(2 * np.pi * t / 7.0 + rng.uniform(0, 6))
    w = 0.6 * np.sin(2 * np.pi * t / 5.0 + rng.uniform(0, 6))
    left = 0.5 + 4.0 * v + 3.0 * np.maximum(-w, 0) + np.maximum(w, 0) + offset_a + 0.1 * rng.standard_normal(t.size)
    right = 0.5 + 4.0 * v + 3.0 * np.maximum(w, 0) + np.maximum(-w, 0) + offset_a + 0.1 * rng.standard_normal(t.size)
    return InteractionLog(t, v, w, left, right, t, np.full(t.size, 9.81),
                          meta=LogMeta(source=f"{ground}/run{seed}", ground_label=ground, robot="husky_a200"))


@pytest.fixture(scope="module")
def linear_model():
    """A linear model with a cross-validated interval from three grounds of four runs: a new ground's forecast is a t
    with 3 dof, a known ground's one with 4 (its runs)."""
    logs = [_run(10 * k + s, g, offset) for k, (g, offset) in enumerate((("a", 0.0), ("b", 0.6), ("c", -0.5)))
            for s in range(4)]
    return fit_interval(LinearCurrentModel(), logs, folds=3)


@pytest.fixture
def world(linear_model, known_model):
    """A 12 x 40 m flat map: grass (bottom strip, priced by the linear model, a ground it never drove), an
    obstacle row, loam (top strip, priced by the known model, Gaussian); one learned cost over both."""
    ground = np.zeros((12, 40), dtype=int)
    ground[6:] = 1
    obstacle = np.zeros((12, 40), dtype=bool)
    obstacle[5] = True
    tmap = TerrainMap(np.zeros((12, 40)), 1.0, ground=ground, ground_names={0: "grass", 1: "loam"},
                      obstacle=obstacle)
    registry = CellModelRegistry.from_terrain(tmap, linear_model, prior_name="linear")
    loam = registry.add_model(known_model(), name="loam")
    registry.assign(ground == 1, loam, reason="the known model's loam")
    lem = LearnedEnergyModel(registry, robot_preset("husky"), ground_preset("asphalt"))
    t = np.arange(0.0, 2.0, 0.01)
    lem.set_vibration(loam, t, np.full(t.size, 9.0))  # the known model tells loam by its vibration level
    return tmap, lem, lem.energy_cost(tmap, 0.5)


def _route(tmap, cost, start, goal):
    route = plan_route(tmap, start, goal, cost=cost, planner="lattice")
    assert route.status == "exact"
    return route


def test_the_model_s_new_ground_dof_reaches_the_cost_rows_and_the_route_interval(linear_model, world):
    tmap, lem, cost = world
    dof = linear_model.interval_.new_ground_dof
    assert dof == 3.0
    # the model's own forecast: a t with as many dof as grounds on a ground it never drove, as runs on one it knows
    assert linear_model.predict_distribution(_run(99, "grass", 0.0)).dof == dof
    assert linear_model.predict_distribution(_run(99, "a", 0.0)).dof == linear_model.interval_.run_dof("a") == 4.0
    assert cost.tables.ground_labels == ("linear", "loam") and cost.tables.spread_dof == (dof, math.inf)
    assert lem.table(lem.registry.prior_id).dof == dof
    iv = price_route(cost, _route(tmap, cost, GRASS_START, GRASS_GOAL))
    assert iv.dof == dof and iv.dof_by_ground == {"linear": dof} and iv.sd_j > 0
    t90 = predictive_quantile(0.9, dof)
    assert iv.p90_j == pytest.approx(iv.mean_j + t90 * iv.sd_j, rel=1e-12)
    assert iv.interval_j(0.8) == pytest.approx((iv.mean_j - t90 * iv.sd_j, iv.mean_j + t90 * iv.sd_j), rel=1e-12)
    assert iv.p50_j == iv.mean_j
    d = iv.to_dict()
    assert d["dof"] == dof and d["distribution"].startswith("student-t with 3 degrees")


def test_plan_with_a_model_reports_the_t_interval_of_a_ground_it_never_drove(linear_model):
    # what `terrawatt plan --model FILE --model-ground a --risk 0.9` reports on a map of grass
    tmap = TerrainMap(np.zeros((6, 30)), 1.0, ground=np.zeros((6, 30), int), ground_names={0: "grass"})
    report = plan_and_compare(tmap, (2.5, 2.5), (27.5, 2.5), search=RouteSearch("lattice"),
                              pricing=CostSpec(model=linear_model, model_ground="a", risk=0.9))
    iv = report.interval
    assert iv.dof == 3.0 and iv.p90_j == pytest.approx(iv.mean_j + predictive_quantile(0.9, 3.0) * iv.sd_j)
    assert report.route.energy_j == pytest.approx(iv.p90_j, rel=1e-9)  # planned on exactly that quantile
    assert "Student-t with 3 dof" in report.summary()
    assert report.to_dict()["routes"]["min_energy"]["energy_interval"]["dof"] == 3.0


def test_at_risk_prices_each_row_at_its_own_predictive_quantile(linear_model, world):
    tmap, _, cost = world
    risky = CostSpec(model=linear_model, risk=0.9).at_risk(cost)
    assert risky.tables.spread_dof == cost.tables.spread_dof
    for row, z in ((0, predictive_quantile(0.9, 3.0)), (1, predictive_quantile(0.9))):
        assert np.allclose(risky.tables.grade_table_j_per_m[row],
                           np.maximum(cost.tables.grade_table_j_per_m[row] + z * cost.tables.grade_sd_table_j_per_m[row], 0))
        assert np.allclose(risky.tables.turn_table_j[row], cost.tables.turn_table_j[row] + z * cost.tables.turn_sd_table_j[row])
    # on one ground the route planned at Q = 0.9 costs exactly its interval's P90
    for start, goal, dof in ((GRASS_START, GRASS_GOAL, 3.0), (LOAM_START, LOAM_GOAL, math.inf)):
        route = _route(tmap, risky, start, goal)
        iv = price_route(cost, route)
        assert iv.dof == dof
        assert route.energy_j == pytest.approx(iv.p90_j, rel=1e-9)


def test_monte_carlo_draws_put_nine_in_ten_missions_below_the_route_p90(world):
    tmap, _, cost = world
    battery = Battery(capacity_ah=40.0, voltage_v=24.0)
    for start, goal, dof in ((GRASS_START, GRASS_GOAL, 3.0), (LOAM_START, LOAM_GOAL, math.inf)):
        route = _route(tmap, cost, start, goal)
        iv = price_route(cost, route)
        mc = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(4000, draw_from="model", seed=7), cost=cost)
        assert mc.forecast == iv and iv.dof == dof
        share = float(np.mean(mc.energy_j <= iv.p90_j))
        assert share == pytest.approx(0.9, abs=0.02)  # 4.5 sampling sd; a Gaussian draw would give 0.95 on grass
        assert float(np.mean(mc.energy_j <= iv.quantile_j(0.99))) == pytest.approx(0.99, abs=0.006)
        assert ("Student-t" in mc.summary()) == math.isfinite(dof)
    again = simulate_missions_mc(tmap, route, battery, MonteCarloStudy(50, draw_from="model", seed=7), cost=cost)
    assert np.array_equal(again.energy_j, mc.energy_j[:50])


def test_the_navigator_reads_its_remaining_forecast_from_the_same_predictive(world):
    tmap, lem, cost = world
    settings = AdaptiveSettings(leg_length_m=8.0, seed=0, risk=0.9, speed_mps=0.5)
    for start, goal, dof in ((GRASS_START, GRASS_GOAL, 3.0), (LOAM_START, LOAM_GOAL, math.inf)):
        nav = Navigator(tmap, lem.registry, lem.robot, Battery(40.0, 24.0), goal, settings=settings,
                        models=NavigatorModels(learned=lem))
        nav.plan(start)
        fc = nav.forecast()
        assert fc.dof == price_route(nav.cost, nav.route).dof == dof
        z_level, z_risk = predictive_quantile(0.5 + fc.level / 2, dof), predictive_quantile(0.9, dof)
        assert (fc.risk_j - fc.energy_j) / (fc.high_j - fc.energy_j) == pytest.approx(z_risk / z_level, rel=1e-9)
        assert ("dof" in fc.to_dict()) == math.isfinite(dof)


def test_degrees_of_freedom_are_checked_where_they_enter(world):
    tmap, _, cost = world
    with pytest.raises(InvalidParameterError, match="one value per table row"):
        cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j, ground_labels=cost.tables.ground_labels, grade_sd_table_j_per_m=cost.tables.grade_sd_table_j_per_m, turn_sd_table_j=cost.tables.turn_sd_table_j, spread_dof=(3.0,)))
    with pytest.raises(InvalidParameterError, match="spread_dof must be > 0"):
        cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j, ground_labels=cost.tables.ground_labels, grade_sd_table_j_per_m=cost.tables.grade_sd_table_j_per_m, turn_sd_table_j=cost.tables.turn_sd_table_j, spread_dof=(0.0, 3.0)))
    with pytest.raises(InvalidParameterError, match="goes with"):
        EnergyCost(tmap, np.zeros(tmap.shape, int), CostTables(cost.tables.grade_table_j_per_m[:1], cost.tables.turn_table_j[:1], spread_dof=(3.0,)), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=0.5)
    with pytest.raises(InvalidParameterError, match="RouteEnergyInterval.dof"):
        RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0}, dof=-1.0)
    with pytest.raises(InvalidParameterError, match="without a spread"):
        RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0}, dof=3.0, dof_by_ground={"clay": 3.0})


def test_a_class_named_as_a_training_ground_is_priced_with_that_ground_s_own_spread(linear_model):
    # class 0 is "a", a ground the model drove; class 1 "grass" is priced as "a" by the user's mapping only
    ground = np.zeros((6, 30), int)
    ground[3:] = 1
    tmap = TerrainMap(np.zeros((6, 30)), 1.0, ground=ground, ground_names={0: "a", 1: "grass"})
    named = CostSpec(model=linear_model, model_ground={"grass": "b"}).build(tmap)
    assert dict(zip(named.tables.ground_labels, named.tables.spread_dof)) == {"a": 4.0, "b": 3.0}  # runs, grounds
    mapped = CostSpec(model=linear_model, model_ground={"a": "b", "grass": "a"}).build(tmap)
    row_named, row_mapped = named.tables.ground_labels.index("a"), mapped.tables.ground_labels.index("a")
    assert mapped.tables.spread_dof[row_mapped] == 3.0  # "a" now also prices grass, a ground the model never drove
    # the ground's own run spread is narrower than the spread of a ground the model never drove
    assert np.all(named.tables.grade_sd_table_j_per_m[row_named] < mapped.tables.grade_sd_table_j_per_m[row_mapped])
