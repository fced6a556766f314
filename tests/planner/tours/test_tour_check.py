"""The tours' Monte Carlo (planner.tours.check): the share above the reserve beside Q."""

from __future__ import annotations

import numpy as np
from tour_samples import hills_cost  # noqa: F401  (fixture)

from energy import Battery
from planner.tours import TourRobot, TourSites, plan_tour, simulate_tours_mc


def test_monte_carlo_of_the_tours_ends_above_the_reserve_about_as_often_as_q(hills_cost):
    rng = np.random.default_rng(5)
    sites = TourSites(tuple(f"s{k}" for k in range(12)), rng.uniform(3.0, 37.0, size=(12, 2)))
    robot = TourRobot(Battery(0.15, 24.0), (20.0, 20.0))
    shares = {}
    for q in (0.5, 0.9):
        res = plan_tour(hills_cost, sites, robot, risk=q)
        check = simulate_tours_mc(res, 400, seed=2)
        shares[q] = check.share_above_reserve
        assert check.draw_from == "model" and "above the reserve" in check.summary()
    assert shares[0.9] >= 0.88
    assert shares[0.5] < shares[0.9] - 0.1  # the knob means something
