"""The wall-map cost and its pairs (west, east, below the gap, on the wall), shared by the batch tests."""

from __future__ import annotations

import pytest

from planner.cost_spec import CostSpec

#: A free cell west of the wall, one east of it, one below the gap and the wall itself (wall_map).
WEST, EAST, EAST_LOW, ON_WALL = (5.5, 10.5), (35.5, 10.5), (30.5, 3.5), (20.5, 10.5)
PAIRS = [[*WEST, *EAST], [*EAST, *WEST], [*WEST, *EAST_LOW], [*EAST_LOW, *EAST]]


@pytest.fixture
def cost(wall_map):
    return CostSpec().build(wall_map)
