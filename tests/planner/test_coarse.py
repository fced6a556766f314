"""Tests of planner.coarse: coarse-to-fine planning against the full-resolution optimum, fallbacks, downsampling, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.cost_spec import CostSpec
from terrain import InvalidParameterError, procedural_map


@pytest.fixture(scope="module")
def hilly_cost():
    return CostSpec().build(procedural_map((120, 112), 1.0, seed=5, obstacle_fraction=0.01))


def test_coarse_to_fine_is_close_to_the_full_resolution_optimum(hilly_cost):
    from planner import CoarseOptions, plan_coarse_to_fine

    plan = plan_coarse_to_fine(hilly_cost, (6.5, 8.5), (104.5, 110.5), CoarseOptions(factor=4), compare=True)
    assert plan.route.status == "exact" and plan.route.planner == "coarse-to-fine"
    assert plan.ratio_to_optimum >= 1.0 - 1e-12
    assert plan.ratio_to_optimum <= 1.02
    # the corridor is a small part of the map, and the route's energy is the corridor objective
    assert 0 < plan.corridor_cells < 0.6 * 120 * 112
    assert plan.route.drive_energy_j == pytest.approx(plan.objective_j, rel=1e-9)
    assert np.allclose(plan.route.waypoints_m[[0, -1]], [[6.5, 8.5], [104.5, 110.5]])
    assert plan.coarse_waypoints_m.shape[0] >= 2 and plan.fallback == "none"


def test_a_narrow_corridor_is_never_below_the_optimum(hilly_cost):
    from planner import CoarseOptions, plan_coarse_to_fine

    for factor, corridor_m in ((2, 1.0), (8, 4.0), (3, 30.0)):
        options = CoarseOptions(factor=factor, corridor_m=corridor_m)
        plan = plan_coarse_to_fine(hilly_cost, (10.5, 100.5), (100.5, 10.5), options, compare=True)
        assert plan.route.status == "exact"
        assert plan.ratio_to_optimum >= 1.0 - 1e-12


def test_a_passage_the_coarse_map_cannot_see_falls_back():
    from planner import CoarseOptions, plan_coarse_to_fine
    from terrain import wall_map

    # a 1-cell gap in a wall: blocks of 8 cells over the wall are mostly free, the coarse
    # route goes straight through where the fine wall is closed
    tmap = wall_map((64, 64), 1.0, wall_col=32, gap_rows=(60, 61), ground="asphalt")
    cost = CostSpec().build(tmap)
    plan = plan_coarse_to_fine(cost, (4.5, 4.5), (60.5, 4.5), CoarseOptions(factor=8, corridor_m=2.0), compare=True)
    assert plan.route.status == "exact"
    assert plan.fallback in ("wider corridor", "whole map")
    assert plan.ratio_to_optimum == pytest.approx(1.0, abs=1e-9)


def test_separated_points_are_infeasible():
    from planner import CoarseOptions, plan_coarse_to_fine
    from terrain import wall_map

    tmap = wall_map((32, 32), 1.0, wall_col=16, gap_rows=(0, 0), ground="asphalt")
    plan = plan_coarse_to_fine(CostSpec().build(tmap), (4.5, 4.5), (28.5, 4.5), CoarseOptions(factor=4))
    assert plan.route.status == "infeasible" and math.isnan(plan.ratio_to_optimum)


def test_downsampled_cost(hilly_cost):
    from planner.coarse import downsample_cost

    coarse = downsample_cost(hilly_cost, 4)
    assert coarse.shape == (30, 28) and coarse.terrain.cell_size_m == 4.0
    assert coarse.terrain.elevation_m[0, 0] == pytest.approx(hilly_cost.terrain.elevation_m[:4, :4].mean())
    odd = downsample_cost(hilly_cost, 5)  # 120 x 112 is not a multiple of 5: edge-padded
    assert odd.shape == (24, 23)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"factor": 1}, "factor must be >= 2"),
        ({"factor": 2.5}, "factor"),
        ({"factor": 100_000}, "fewer than 2 x 2"),
        ({"corridor_m": 0.0}, "corridor_m must be > 0"),
        ({"corridor_m": float("inf")}, "corridor_m must be finite"),
        ({"compare": "yes"}, "compare must be True or False"),
    ],
)
def test_bad_coarse_to_fine_arguments(hilly_cost, kwargs, match):
    from planner import CoarseOptions, plan_coarse_to_fine

    compare = kwargs.pop("compare", False)
    with pytest.raises(InvalidParameterError, match=match):
        plan_coarse_to_fine(hilly_cost, (6.5, 8.5), (100.5, 100.5), CoarseOptions(**kwargs), compare=compare)


def test_bad_coarse_to_fine_points(hilly_cost):
    from planner import plan_coarse_to_fine
    from terrawatt_base.errors import OutOfBoundsError

    with pytest.raises(OutOfBoundsError):
        plan_coarse_to_fine(hilly_cost, (-1.0, 8.5), (100.5, 100.5))
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        plan_coarse_to_fine(hilly_cost, (6.5, 8.5), (6.5, 8.5))
    with pytest.raises(InvalidParameterError, match="source must be an EnergyCost .* or the path of a GeoTIFF"):
        plan_coarse_to_fine(3.0, (6.5, 8.5), (100.5, 100.5))
    with pytest.raises(InvalidParameterError, match="options must be a CoarseOptions"):
        plan_coarse_to_fine(hilly_cost, (6.5, 8.5), (100.5, 100.5), {"factor": 4})
    with pytest.raises(InvalidParameterError, match="cost_from prices the windows of a GeoTIFF"):
        plan_coarse_to_fine(hilly_cost, (6.5, 8.5), (100.5, 100.5), cost_from=CostSpec())


def test_coarse_to_fine_refuses_a_blocked_start(tmp_path):
    from planner import plan_coarse_to_fine
    from terrain import wall_map
    from terrawatt_base.errors import BlockedPositionError

    cost = CostSpec().build(wall_map((32, 32), 1.0, wall_col=16, ground="asphalt"))
    with pytest.raises(BlockedPositionError, match="start_xy_m .* blocked cell"):
        plan_coarse_to_fine(cost, (16.5, 4.5), (28.5, 4.5))
