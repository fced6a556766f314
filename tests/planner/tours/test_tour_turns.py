"""The turn at each stop (planner.tours): a tour is priced as the route the robot drives, and its budget is checked on
that price."""

from __future__ import annotations

import numpy as np
import pytest
from tour_samples import with_interval

import planner.tours.solver as solver
from energy import Battery
from planner import price_route
from planner.cost_spec import CostSpec
from planner.tours import TourRobot, TourSearch, TourSites, plan_tour, price_pairs
from planner.tours.tour import NOT_WORTH_IT, TOO_FAR
from terrain import flat_map

DEPOT = (2.5, 5.5)
SITE = (30.5, 5.5)  # due east of the depot: the robot leaves it the way it came, a U-turn there


@pytest.fixture(scope="module")
def corridor():
    """A flat 40 m x 12 m strip with a spread, the depot and the site on one line, their legs and the U-turn."""
    cost = with_interval(CostSpec().build(flat_map((12, 40), 1.0)))
    prices = price_pairs(cost, [DEPOT, SITE], ("depot", "site"))
    legs = prices.mean_j[0, 1] + prices.mean_j[1, 0]
    joined = np.vstack([prices.waypoints[0][1], prices.waypoints[1][0][1:]])
    return cost, prices, legs, price_route(cost, joined)


def _battery(budget_j: float) -> Battery:
    return Battery(budget_j / (0.8 * 24.0 * 3600.0), 24.0, min_reserve_pct=20.0)


def test_the_tours_price_is_the_joined_routes_u_turn_included(corridor):
    cost, _, legs, joined = corridor
    assert joined.mean_j > legs + 500.0  # the U-turn at the site: no leg prices it
    res = plan_tour(cost, TourSites(("site",), [SITE]), TourRobot(Battery(1.0, 24.0), DEPOT))
    tour = res.tours[0]
    assert tour.sites == ("site",)
    exact = price_route(cost, res.tour_route(0).waypoints_m)
    assert tour.energy.mean_j == pytest.approx(exact.mean_j, rel=1e-9)
    assert tour.energy.quantile_j(0.9) == pytest.approx(exact.quantile_j(0.9), rel=1e-9)
    assert tour.energy.sd_by_ground_j == pytest.approx(exact.sd_by_ground_j, rel=1e-9)
    assert sum(leg.energy.mean_j for leg in tour.legs) == pytest.approx(exact.mean_j, rel=1e-9)  # legs add up to it
    assert tour.legs[1].energy.mean_j > tour.legs[0].energy.mean_j + 500.0  # the leg leaving the site turns first


def test_the_budget_is_checked_on_the_exact_price(corridor):
    cost, _, legs, joined = corridor
    sites = TourSites(("site",), [SITE])
    at_q = joined.quantile_j(0.9)
    short = plan_tour(cost, sites, TourRobot(_battery(0.5 * (legs * 1.3 + at_q)), DEPOT))  # legs fit, the U-turn not
    assert short.visited == () and short.left_out["site"] in (TOO_FAR, NOT_WORTH_IT)
    enough = plan_tour(cost, sites, TourRobot(_battery(1.01 * at_q), DEPOT))
    assert enough.visited == ("site",)
    assert enough.tours[0].energy.quantile_j(0.9) <= enough.tours[0].budget_j


def test_a_tour_still_above_its_budget_after_the_last_round_loses_stops(corridor, monkeypatch):
    cost, prices, legs, joined = corridor
    allowance = prices.stop_turn_quantile_j(0.9)[1]
    matrix_j = prices.arc_quantile_j(0.9)[0, 1] + prices.arc_quantile_j(0.9)[1, 0] + allowance
    budget = 0.5 * (matrix_j + joined.quantile_j(0.9))  # the matrix takes the site, its exact price does not fit
    assert matrix_j < budget < joined.quantile_j(0.9)
    robot = TourRobot(_battery(budget), DEPOT)
    monkeypatch.setattr(solver, "_MAX_ROUNDS", 1)  # no round left to raise the site's allowance
    res = plan_tour(cost, TourSites(("site",), [SITE]), robot, prices=prices, search=TourSearch(risk=0.9))
    assert res.visited == () and res.left_out == {"site": NOT_WORTH_IT}
    monkeypatch.undo()
    again = plan_tour(cost, TourSites(("site",), [SITE]), robot, prices=prices, search=TourSearch(risk=0.9))
    assert again.visited == () and again.solve_rounds == 2  # the allowance raised to the U-turn, solved again


def test_a_site_passed_straight_through_pays_its_stop_and_go_and_its_time():
    # depot, near and far on one line: the tour drives straight on through one site and turns back at the other
    cost = CostSpec().build(flat_map((12, 40), 1.0))
    sites = TourSites(("near", "far"), [(15.5, 5.5), (30.5, 5.5)])
    res = plan_tour(cost, sites, TourRobot(Battery(1.0, 24.0), DEPOT))
    tour, prices = res.tours[0], res.prices
    assert set(tour.sites) == {"near", "far"}
    seq = [0, *(prices.names.index(s) for s in tour.stops), 0]
    triples = list(zip(seq, seq[1:], seq[2:]))
    turns = [prices.turn_time_s(*t) for t in triples]
    through = turns.index(0.0)  # driven straight on there: no pivot ...
    assert turns[1 - through] == pytest.approx(np.pi / 0.5 + 0.5)  # a U-turn at 0.5 rad/s, ramped at 1 rad/s^2
    assert float(cost.stop_go_at([0])[0]) > 10.0
    # ... but a stop: the tour pays the stop-and-go at every site (each leg's own, from rest to rest) and the pivot
    legs = sum(prices.mean_j[a, b] for a, b in zip(seq[:-1], seq[1:]))
    assert prices.turn_interval(*triples[through]).mean_j == pytest.approx(0.0, abs=1e-6)
    pivot = prices.turn_interval(*triples[1 - through]).mean_j
    assert tour.energy.mean_j == pytest.approx(legs + pivot, rel=1e-9)
    # and its time: each leg driven from rest to rest (13 m at 0.5 m/s plus 1 s of ramps), each pivot after serving
    assert prices.duration_s[0, prices.names.index("near")] == pytest.approx(13.0 / 0.5 + 1.0)
    drive = prices.duration_s
    assert tour.arrival_s[1] == pytest.approx(drive[0, seq[1]] + turns[0] + drive[seq[1], seq[2]])
    assert tour.return_s == pytest.approx(tour.arrival_s[1] + turns[1] + drive[seq[2], 0])
    assert tour.duration_s == pytest.approx(tour.return_s)  # no service, no wait: the legs' times add up
