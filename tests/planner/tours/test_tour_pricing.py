"""Pricing every ordered pair (planner.tours.pricing): one search per point equals the pairwise optimum."""

from __future__ import annotations

import numpy as np
import pytest

from planner import Lattice

from tour_samples import hills_cost  # noqa: F401  (fixture)


def test_paths_from_one_search_equals_the_pairwise_optimum(hills_cost):
    lat = Lattice.for_cost(hills_cost)
    goals = np.array([[5.0, 5.0], [35.5, 30.2], [14.0, 26.0], [30.0, 3.0]])
    for path, goal in zip(lat.paths_from((20.0, 20.0), goals), goals):
        assert path.objective == pytest.approx(lat.shortest_path((20.0, 20.0), tuple(goal)).objective, rel=1e-12)
