"""Tests of planner.missions.request: MissionRequest checks its options together and places start and goal."""

from __future__ import annotations

import re

import numpy as np
import pytest

import terrain
from planner.missions.request import MISSION_OPTIONS, MissionRequest
from terrain import InvalidParameterError, OutOfBoundsError, TerrainMap, UnknownNameError
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

_FLAGS = {"start": "--start", "start_lonlat": "--start-lonlat", "goal": "--goal", "goal_lonlat": "--goal-lonlat",
          "prior_ground": "--prior-ground", "monte_carlo": "--monte-carlo", "workers": "--workers",
          "scheduler": "--scheduler", "model": "--model", "risk": "--risk", "draw_from": "--mc-draw"}


def test_every_option_has_a_flag_name_here():
    assert set(_FLAGS) == set(MISSION_OPTIONS)


@pytest.mark.parametrize(
    ("options", "error", "message"),
    [({"prior_ground": "lava"}, UnknownNameError, "--prior-ground 'lava' has no preset; known grounds: ['asphalt'"),
     ({"workers": 2}, InvalidParameterError, "--workers and --scheduler apply to --monte-carlo N only"),
     ({"scheduler": "tcp://h:1"}, InvalidParameterError, "--workers and --scheduler apply to --monte-carlo N only"),
     ({"monte_carlo": 0}, InvalidParameterError, "--monte-carlo"),
     ({"monte_carlo": 3, "workers": 0}, InvalidParameterError, "--workers must be a positive number of processes"),
     ({"monte_carlo": 3, "workers": 2, "scheduler": "tcp://h:1"}, InvalidParameterError, "exclude each other"),
     ({"risk": 0.9}, InvalidParameterError, "--risk Q of mission checks the route's Q quantile against the usable "
                                            "battery in a --monte-carlo N study; the adaptive mission does not take "
                                            "it yet"),
     ({"monte_carlo": 3, "risk": 1.0}, InvalidParameterError, "--risk"),
     ({"monte_carlo": 3, "draw_from": "model"}, InvalidParameterError,
      "--mc-draw model draws from a saved model's predictive distribution: give --model FILE"),
     ({"monte_carlo": 3, "draw_from": "posterior"}, UnknownNameError, "--mc-draw must be one of"),
     ({"on_example": False, "start": (1.0, 1.0)}, InvalidParameterError,
      "--start and --goal (or --start-lonlat and --goal-lonlat) are required with a map file"),
     ({"on_example": False, "goal_lonlat": (15.0, 45.0)}, InvalidParameterError, "are required with a map file")],
)
def test_options_that_do_not_go_together_are_refused_when_made(options, error, message):
    with pytest.raises(error, match=re.escape(message)):
        MissionRequest(**options, names=_FLAGS)


def test_options_that_go_together_pass_and_unnamed_options_are_named_as_themselves():
    MissionRequest(monte_carlo=4, workers=2, risk=0.9, draw_from="model", model="m.zip")
    MissionRequest(on_example=False, start_lonlat=(15.0, 45.0), goal=(1.0, 2.0), prior_ground="sand")
    with pytest.raises(InvalidParameterError, match="^workers and scheduler apply to monte_carlo N only$"):
        MissionRequest(workers=2)


def test_points_default_to_the_examples_on_the_example_map():
    assert MissionRequest().points(example_map()) == (EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M)
    start, goal = MissionRequest(start=(30, 40)).points(example_map())
    assert start == (30.0, 40.0) and goal == EXAMPLE_GOAL_XY_M


def test_points_in_degrees_are_placed_by_the_maps_crs():
    tmap = TerrainMap(np.zeros((40, 40)), 30.0, (500000.0, 4982900.0), crs="EPSG:32633")
    start, goal = MissionRequest(on_example=False, start_lonlat=(15.0, 45.0), goal=(500100.0, 4983000.0)).points(tmap)
    assert start == pytest.approx((500000.0, 4982950.4), abs=0.1) and goal == (500100.0, 4983000.0)
    with pytest.raises(OutOfBoundsError, match="--goal-lonlat"):
        MissionRequest(on_example=False, start=(500100.0, 4983000.0), goal_lonlat=(16.0, 45.0),
                       names=_FLAGS).points(tmap)


def test_points_need_every_ground_of_the_map_a_preset():
    ground = np.zeros((10, 10), dtype=int)
    tmap = terrain.TerrainMap(np.zeros((10, 10)), 1.0, ground=ground, ground_names={0: "moss"})
    with pytest.raises(UnknownNameError, match=r"the map's grounds \['moss'\] have no preset"):
        MissionRequest(on_example=False, start=(1, 1), goal=(8, 8)).points(tmap)
