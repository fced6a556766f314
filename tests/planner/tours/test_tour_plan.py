"""plan_tour (planner.tours.tour): the exhaustive optimum, the risk level, uphill != downhill, nothing reachable."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from tour_samples import exact_fleet_optimum, exact_optimum, hills_cost, hills_map, ridge_map, with_interval  # noqa: F401  (fixture)

from energy import Battery
from planner import EnergyCost
from planner.cost_spec import CostSpec
from planner.tours import TourPoints, TourProblem, TourRobot, TourSearch, TourSites, plan_tour, price_pairs
from planner.tours.solver import VALUE_SCALE, solve_pyvrp
from planner.tours.tour import NOT_WORTH_IT, TOO_FAR
from terrain import flat_map


def _exhaustive(problem: TourProblem) -> float:
    """The best value over every assignment of the candidates to the robots and every order (1 or 2 robots)."""
    sites = problem.site_points.tolist()
    value = dict(zip(sites, problem.prize.tolist()))
    best = 0
    n_robots = len(problem.depot_points)
    for k in range(len(sites) + 1):
        for seq in itertools.permutations(sites, k):
            splits = [(seq,)] if n_robots == 1 else [(seq[:i], seq[i:]) for i in range(k + 1)]
            for tours in splits:
                if all(problem.tour_units(r, t) <= problem.capacity_units[r] for r, t in enumerate(tours)):
                    best = max(best, sum(value[s] for s in seq))
    return best


def _problem(cost: EnergyCost, sites: TourSites, robots: list[TourRobot], q: float) -> TourProblem:
    """The integer problem plan_tour solves, built from the same pricing (one depot)."""
    depot = robots[0].depot_xy_m
    pts = np.vstack([depot, sites.xy_m])
    prices = price_pairs(cost, pts, ("depot", *sites.names), risk=q)
    value = np.concatenate([[0.0], sites.value])
    return TourProblem.build(prices, q, [r.budget_j for r in robots], [0] * len(robots), np.arange(1, len(pts)),
                             TourPoints(value, np.concatenate([[0.0], sites.service_energy_j])))


@pytest.mark.parametrize("n_sites, n_robots, q, ah", [(8, 1, 0.9, 0.12), (8, 1, 0.5, 0.12), (6, 2, 0.9, 0.06)])
def test_the_tours_value_equals_the_exhaustive_optimum(hills_cost, n_sites, n_robots, q, ah):
    """The value equals the best over every subset, split and order priced as the robot drives it (the turns at its
    stops). At q = 0.5 the matrix's own optimum (value 7, :func:`_exhaustive`: its quarter-turn allowances
    under-price that order's turns) breaks its budget once driven: the exact optimum is 5."""
    rng = np.random.default_rng(n_sites + n_robots)
    xy = rng.uniform(3.0, 37.0, size=(n_sites, 2))
    sites = TourSites(tuple(f"s{k}" for k in range(n_sites)), xy, value=rng.integers(1, 6, n_sites).astype(float))
    robots = [TourRobot(Battery(ah, 24.0, min_reserve_pct=20.0), (20.0, 20.0), f"r{k}") for k in range(n_robots)]
    res = plan_tour(hills_cost, sites, robots, search=TourSearch(risk=q, seed=1))
    assert res.status == "planned"
    assert 0 < res.value < sites.value.sum()  # the battery binds: a real choice
    value = {k + 1: float(v) for k, v in enumerate(sites.value)}
    assert res.value == exact_fleet_optimum(res.prices, [r.budget_j for r in robots], q, value)
    if n_robots == 1:  # the fleet's exhaustive search agrees with the one robot's (pruned at every prefix)
        assert res.value == exact_optimum(res.prices, robots[0].budget_j, q, value)
    if q == 0.5:  # the matrix's optimum is not the one the robot can drive
        problem = _problem(hills_cost, sites, robots, q)
        assert _exhaustive(problem) == 7 * VALUE_SCALE * (int(problem.capacity_units.sum()) + 1)
    for tour in res.tours:  # every tour holds at its own quantile
        assert tour.energy.quantile_j(q) <= tour.budget_j
        assert tour.arrival_soc_at_risk >= tour.battery.reserve_soc - 1e-12
    assert set(res.visited) | set(res.left_out) == set(sites.names)


def test_a_higher_risk_level_visits_no_more():
    cost = with_interval(CostSpec().build(hills_map()), rel_sd=0.3)
    rng = np.random.default_rng(3)
    sites = TourSites(tuple(f"s{k}" for k in range(7)), rng.uniform(3.0, 37.0, size=(7, 2)))
    robot = TourRobot(Battery(0.1, 24.0), (20.0, 20.0))
    values = [plan_tour(cost, sites, robot, search=TourSearch(risk=q)).value for q in (0.5, 0.9, 0.99)]
    assert values[0] >= values[1] >= values[2] and values[0] > values[2]


def test_uphill_and_downhill_priced_apart_choose_the_cheaper_direction():
    """Over a ridge a loop costs another energy each way round; a symmetric cost prices both the same, so it
    cannot prefer the cheap direction and, with a tight battery, believes the loop does not fit."""
    cost = CostSpec().build(ridge_map())
    sites = TourSites(("west", "east"), [[4.5, 36.5], [36.5, 36.5]])
    depot = (4.5, 4.5)
    prices = price_pairs(cost, np.vstack([depot, sites.xy_m]), ("depot", *sites.names))
    assert prices.mean_j[1, 2] > 1.3 * prices.mean_j[2, 1]  # west -> east goes round the ridge, east -> west over it
    cheap, dear = prices.tour_interval([0, 2, 1, 0]).mean_j, prices.tour_interval([0, 1, 2, 0]).mean_j
    assert dear > 1.1 * cheap
    res = plan_tour(cost, sites, TourRobot(Battery(5.0, 24.0), depot))
    assert res.tours[0].sites == ("east", "west") and res.tours[0].energy.mean_j == pytest.approx(cheap)
    symmetric = dataclasses.replace(prices, mean_j=(prices.mean_j + prices.mean_j.T) / 2)
    loop = lambda m, seq: float(sum(m[a, b] for a, b in zip(seq[:-1], seq[1:])))  # noqa: E731 (the legs summed)
    sym_legs = loop(symmetric.mean_j, [0, 1, 2, 0])
    assert sym_legs == pytest.approx(loop(symmetric.mean_j, [0, 2, 1, 0]))
    assert sym_legs == pytest.approx((loop(prices.mean_j, [0, 2, 1, 0]) + loop(prices.mean_j, [0, 1, 2, 0])) / 2)
    # what the symmetric matrix charges the loop: its legs and the allowance for the turns at the two sites
    sym_loop = sym_legs + float(symmetric.stop_turn_quantile_j(0.9)[1:].sum())
    assert cheap < sym_loop
    # a battery between the cheap direction and the symmetric price: both sites, against one by the symmetric cost
    budget_j = (cheap + sym_loop) / 2
    battery = Battery(budget_j / (0.8 * 24.0 * 3600.0), 24.0, min_reserve_pct=20.0)
    tight = plan_tour(cost, sites, TourRobot(battery, depot))
    sym_tours = solve_pyvrp(TourProblem.build(symmetric, 0.9, [budget_j], [0], [1, 2],
                                              TourPoints([0.0, 1.0, 1.0], [0.0] * 3)))
    assert tight.value == 2 and len(sym_tours[0]) == 1
    assert tight.tours[0].energy.mean_j <= budget_j


def test_a_battery_that_reaches_no_site_answers_nothing_reachable():
    cost = CostSpec().build(flat_map((40, 40), 1.0))
    sites = TourSites(("a", "b"), [[30.0, 30.0], [35.0, 5.0]])
    res = plan_tour(cost, sites, TourRobot(Battery(0.001, 24.0), (2.0, 2.0)))
    assert res.status == "nothing reachable" and res.value == 0
    assert res.left_out == {"a": TOO_FAR, "b": TOO_FAR}
    assert "nothing reachable" in res.summary()


def test_sites_all_worth_nothing_are_a_plan_without_tours():
    cost = CostSpec().build(flat_map((20, 20), 1.0))
    res = plan_tour(cost, TourSites(("a",), [[5.0, 5.0]], value=[0.0]), TourRobot(Battery(1.0, 24.0), (2.0, 2.0)))
    assert res.status == "planned" and res.visited == () and res.left_out == {"a": NOT_WORTH_IT}
