"""Tests of planner.missions.figures: the mission and adaptive-mission figures, written as PNGs or drawn into axes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from matplotlib.figure import Figure

from energy import (
    Battery,
    LinearCurrentModel,
    NoiseModel,
    TruthSimulator,
    excitation_commands,
    ground_preset,
    robot_preset,
)
from planner import AdaptiveSettings, CostSpec, run_adaptive_mission, simulate_mission
from planner.missions import Navigator, NavigatorModels
from planner.missions.figures import plot_adaptive_mission, plot_mission
from planner.registry import CellModelRegistry
from planner.route import evaluate_route
from terrain import InvalidParameterError, TerrainMap, flat_map

ROBOT = robot_preset("husky")
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def mission():
    grounds = {"asphalt": ground_preset("asphalt")}
    tmap = flat_map((12, 20), 1.0)
    cost = CostSpec(robot=ROBOT, grounds=grounds, speed_mps=0.5).build(tmap)
    truth = TruthSimulator(ROBOT, grounds, noise=NoiseModel.off(), current_rate_hz=20.0, seed=0)
    route = evaluate_route(cost, [[2.5, 2.5], [16.5, 2.5], [16.5, 9.5]])
    return simulate_mission(tmap, route, ROBOT, Battery(20.0, 24.0), truth=truth, cost=cost), tmap


@pytest.fixture(scope="module")
def adaptive():
    """A short adaptive mission across a patch of sand the asphalt prior does not know."""
    grounds = {"asphalt": ground_preset("asphalt"), "sand": ground_preset("sand")}
    truth = TruthSimulator(ROBOT, grounds, seed=0)
    ground = np.zeros((16, 40), int)
    ground[4:12, 12:34] = 1
    tmap = TerrainMap(np.zeros((16, 40)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    drive = excitation_commands(20.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=1)
    turn = excitation_commands(8.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                               hold_s=(2.0, 3.0), rest_s=0.0, seed=2)
    logs = [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt", seed=3 + i)
            for i, p in enumerate((drive, turn))]
    registry = CellModelRegistry.from_terrain(tmap, LinearCurrentModel().fit(logs))
    res = run_adaptive_mission(Navigator(tmap, registry, ROBOT, Battery(20.0, 24.0), (37.5, 8.0),
                                         settings=AdaptiveSettings(leg_length_m=8.0, seed=0, max_updates=1),
                                         models=NavigatorModels(physics_ground=grounds["asphalt"])), truth, (2.5, 8.0))
    return res, tmap, registry


def test_the_mission_figure_draws_into_the_callers_axes(mission, tmp_path):
    res, tmap = mission
    fig = Figure()
    panels = fig.subplots(1, 3)
    out = res.plot(terrain=tmap, ax=panels, title="mine")
    assert out == tuple(panels)
    soc, energy, where = out
    assert soc.get_ylabel() == "state of charge (%)" and soc.get_title() == "mine" and soc.lines
    assert energy.get_ylabel() == "cumulative energy (Wh)" and len(energy.lines) == 2
    assert len(where.images) == 2 and len(where.collections) == 1  # elevation, obstacles; the coloured path
    assert len(fig.axes) == 4 and fig.axes[3].get_ylabel() == "battery power (W)"  # colour bar beside the map
    assert fig.get_suptitle() == "" and list(tmp_path.iterdir()) == []


def test_the_mission_figure_takes_a_path_or_three_axes(mission, tmp_path):
    res, tmap = mission
    panels = Figure().subplots(1, 3)
    with pytest.raises(InvalidParameterError, match="got neither"):
        plot_mission(res, terrain=tmap)
    with pytest.raises(InvalidParameterError, match="not both"):
        plot_mission(res, tmp_path / "m.png", tmap, ax=panels)
    with pytest.raises(InvalidParameterError, match=r"3 matplotlib Axes \(state of charge, cumulative energy, map\)"):
        res.plot(ax=panels[:2])
    (tmp_path / "taken.png").mkdir()
    with pytest.raises(InvalidParameterError, match="is a directory"):  # checked before drawing
        res.plot(tmp_path / "taken.png")
    assert not any(ax.has_data() for ax in panels)


def test_the_adaptive_figure_is_written_or_drawn_into_four_axes(adaptive, tmp_path):
    res, tmap, registry = adaptive
    out = res.plot(tmp_path / "adaptive.png", terrain=tmap, registry=registry)
    assert out == tmp_path / "adaptive.png" and out.read_bytes()[:8] == PNG
    fig = Figure()
    grid = fig.subplots(2, 2)
    drawn = plot_adaptive_mission(res, terrain=tmap, registry=registry, ax=grid)
    assert drawn == tuple(grid.ravel())
    assert [ax.get_title() for ax in drawn[:2]] == ["cells by model", "cells by observed error"]
    assert all(ax.images for ax in drawn[:2]) and all(ax.lines for ax in drawn)
    assert drawn[2].get_ylabel() == "state of charge (%)" and drawn[3].get_ylabel() == "cumulative energy (Wh)"
    assert len(fig.axes) == 5 and fig.get_suptitle() == ""  # the error map's colour bar; no suptitle
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adaptive.png"]
    own = Figure().subplots(2, 2)  # a mission's result carries its map and registry: plot needs no more
    assert dataclasses.replace(res, terrain=tmap, registry=registry).plot(ax=own) == tuple(own.ravel())
    assert own[0, 0].get_title() == "cells by model"


def test_the_adaptive_figure_needs_its_map_and_registry_and_one_target(adaptive, tmp_path):
    res, tmap, registry = adaptive
    grid = Figure().subplots(2, 2)
    with pytest.raises(InvalidParameterError, match="got neither"):
        res.plot(terrain=tmap, registry=registry)
    with pytest.raises(InvalidParameterError, match="not both"):
        res.plot(tmp_path / "a.png", terrain=tmap, registry=registry, ax=grid)
    with pytest.raises(InvalidParameterError, match="registry must be the CellModelRegistry"):
        res.plot(terrain=tmap, ax=grid)
    with pytest.raises(InvalidParameterError, match="terrain must be the TerrainMap"):
        plot_adaptive_mission(res, registry=registry, ax=grid)
    with pytest.raises(InvalidParameterError, match=r"4 matplotlib Axes .*got 2"):
        res.plot(terrain=tmap, registry=registry, ax=grid[0])
    assert not any(ax.has_data() for ax in grid.ravel()) and list(tmp_path.iterdir()) == []
