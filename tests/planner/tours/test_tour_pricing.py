"""Pricing every ordered pair (planner.tours.pricing): one search per point equals the pairwise optimum."""

from __future__ import annotations

import numpy as np
import pytest
from tour_samples import hills_cost  # noqa: F401  (fixture)

from planner import Lattice


def test_paths_from_one_search_equals_the_pairwise_optimum(hills_cost):
    lat = Lattice.for_cost(hills_cost)
    goals = np.array([[5.0, 5.0], [35.5, 30.2], [14.0, 26.0], [30.0, 3.0]])
    for path, goal in zip(lat.paths_from((20.0, 20.0), goals), goals):
        assert path.objective == pytest.approx(lat.shortest_path((20.0, 20.0), tuple(goal)).objective, rel=1e-12)


def test_a_ground_the_model_never_drove_prices_arcs_and_tours_at_its_student_t_quantile():
    import math

    from energy.models.forecast import predictive_quantile
    from planner.tours.pricing import PairPrices
    from terrawatt_base.errors import InvalidParameterError

    mean = np.array([[0.0, 100.0, 50.0], [100.0, 0.0, 80.0], [50.0, 80.0, 0.0]])
    sd = np.zeros((3, 3, 2))
    sd[0, 1, 0] = sd[1, 0, 0] = 10.0  # legs 0 <-> 1 on "new" (t, 3 dof); 1 <-> 2 on "known" (Gaussian)
    sd[1, 2, 1] = sd[2, 1, 1] = 8.0
    prices = PairPrices(("d", "a", "b"), np.zeros((3, 2)), mean, sd, ("new", "known"), np.ones((3, 3)),
                        tuple((None,) * 3 for _ in range(3)), 0.0, ground_dof=(3.0, math.inf))
    arcs = prices.arc_quantile_j(0.9)
    assert arcs[0, 1] == pytest.approx(100.0 + predictive_quantile(0.9, 3.0) * 10.0)
    assert arcs[1, 2] == pytest.approx(80.0 + predictive_quantile(0.9) * 8.0)
    assert arcs[0, 2] == 50.0  # no spread: the mean
    with pytest.raises(InvalidParameterError, match="no cost to price a tour"):  # a matrix by hand prices no tour
        prices.tour_interval([0, 1, 2, 0])
