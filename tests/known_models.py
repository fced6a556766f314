"""Test fixtures of the planner and the command line: a current model with a known mean and run-level spread per ground, and a two-corridor map."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from energy import CurrentModel, InteractionLog, LogMeta
from energy.models.forecast import CurrentForecast
from terrain import TerrainMap

#: name -> (vibration level m/s^2, drive current A, turn current A, run-level sd A)
KNOWN_GROUNDS = {"loam": [9.0, 2.0, 4.0, 1.0], "gravel": [10.5, 2.5, 4.5, 0.0]}


class GroundKeyedModel(CurrentModel):
    """Test-only model: tells the ground from the mean vertical acceleration it is fed (its
    recorded vibration is a constant level per ground) and predicts that ground's known
    constant current driving / turning, with a known run-level spread while moving."""

    _param_names = ("grounds", "recorded")

    def __init__(self, grounds: Any = None, recorded: Any = None) -> None:
        self.grounds = KNOWN_GROUNDS if grounds is None else grounds
        self.recorded = list(self.grounds) if recorded is None else recorded

    def _fit(self, logs: list[InteractionLog]) -> None:
        self.fitted_ = True

    def _ground(self, log: InteractionLog) -> list[float]:
        level = float(np.mean(log.accel_z_mps2))
        return min(self.grounds.values(), key=lambda g: abs(g[0] - level))

    def _predict(self, log: InteractionLog) -> np.ndarray:
        _, drive, turn, _ = self._ground(log)
        cur = np.where(np.abs(log.v_mps) > 0, drive, np.where(np.abs(log.omega_radps) > 0, turn, 0.0))
        return np.column_stack([cur, cur])

    def _predict_distribution(self, log: InteractionLog) -> CurrentForecast:
        mean = self.predict(log)
        sd = self._ground(log)[3]
        moving = (np.abs(log.v_mps) > 0) | (np.abs(log.omega_radps) > 0)
        run = np.where(moving, sd, 0.0)
        return CurrentForecast(log.time_s, mean, np.column_stack([run, run]), np.zeros_like(mean))

    @property
    def gives_interval(self) -> bool:
        return any(g[3] > 0 for g in self.grounds.values())

    @property
    def uses_vibration(self) -> bool:
        return True

    def ground_vibration(self, ground: str) -> tuple[np.ndarray, np.ndarray] | None:
        for name, g in self.grounds.items():
            if name.lower() == ground.lower() and name in self.recorded:
                t = np.arange(0.0, 2.0, 0.01)
                return t, np.full(t.size, g[0])
        return None

    def _state(self) -> dict[str, Any]:
        return {"fitted": True}

    def _load_state(self, state: dict[str, Any]) -> None:
        self.fitted_ = bool(state["fitted"])


def training_logs(robot: str, grounds: list[str]) -> list[InteractionLog]:
    """One short log per ground, named robot: what a training summary records."""
    n = 50
    t = np.arange(n) / 10.0
    z = np.zeros(n)
    return [InteractionLog(t, np.full(n, 0.5), z, z + 2, z + 2, t, np.full(n, 9.81),
                           meta=LogMeta(robot=robot, ground_label=g)) for g in grounds]


@pytest.fixture
def known_model():
    """Make a fitted GroundKeyedModel: ``known_model(robot="husky_a200", trained_on=("loam", "gravel"), **params)``."""
    def make(robot: str = "husky_a200", trained_on: tuple[str, ...] = ("loam", "gravel"), **params: Any):
        return GroundKeyedModel(**params).fit(training_logs(robot, list(trained_on)))
    return make


@pytest.fixture
def corridor_map() -> TerrainMap:
    """15 x 30 flat cells of 1 m: two hubs of gravel (x < 5 m, x >= 25 m, y in [2, 13) m) joined by two
    corridors of equal shape, loam at the top (y in [10, 13) m) and gravel at the bottom (y in [2, 5) m);
    everything else is an obstacle. A route from (2.5, 7.5) to (27.5, 7.5) takes one of the two corridors."""
    ground = np.ones((15, 30), dtype=int)  # gravel
    obstacle = np.ones((15, 30), dtype=bool)
    obstacle[2:13, 0:5] = obstacle[2:13, 25:30] = False
    obstacle[2:5, 5:25] = False
    obstacle[10:13, 5:25] = False
    ground[10:13, 5:25] = 0  # loam
    return TerrainMap(np.zeros((15, 30)), 1.0, ground=ground, ground_names={0: "Loam", 1: "gravel"},
                      obstacle=obstacle)
