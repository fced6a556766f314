"""The edge costs of a map for a plan: the physics presets of a robot, or a saved current model."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from energy.params import RobotParams, robot_params
from terrain import TerrainMap

from .edge_cost import DEFAULT_MAX_SLOPE_RAD, EnergyCost
from .model_cost import model_energy_cost

__all__ = ["edge_costs"]


def edge_costs(
    terrain: TerrainMap,
    *,
    robot: str | os.PathLike[str] | RobotParams = "husky",
    speed_mps: float = 0.5,
    max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
    unknown_ground: str | None = "gravel",
    model: Any = None,
    model_ground: str | Mapping[str, str] | None = None,
) -> EnergyCost:
    """The edge costs of ``terrain``: :meth:`EnergyCost.from_presets`, or the saved ``model``'s.

    Parameters
    ----------
    terrain : TerrainMap
        The map to price.
    robot : str, path or RobotParams
        A robot preset name, a robot file (``.json``) or a :class:`~energy.RobotParams`
        (:func:`energy.params.robot_params`).
    speed_mps : float
        Planning speed (m/s).
    max_slope_rad : float
        Steepest drivable slope (rad).
    unknown_ground : str or None
        Presets only: the ground preset of cells of unknown ground (None refuses them).
    model : CurrentModel, optional
        A fitted current model (e.g. :func:`energy.load_current_model`): the edges are priced
        by :func:`planner.model_energy_cost` on ``robot_params(robot)``; ``unknown_ground`` does
        not apply.
    model_ground : str or mapping, optional
        With ``model``: as :func:`planner.model_energy_cost`.

    Returns
    -------
    EnergyCost

    Raises
    ------
    TerrawattError
        As :meth:`EnergyCost.from_presets` or :func:`planner.model_energy_cost`.

    Examples
    --------
    >>> from terrain import flat_map
    >>> edge_costs(flat_map((4, 4), 1.0, ground="asphalt")).terrain.shape
    (4, 4)
    """
    params = robot_params(robot)  # a preset, a robot file or RobotParams: resolved once
    if model is None:
        return EnergyCost.from_presets(terrain, robot=params, speed_mps=speed_mps, max_slope_rad=max_slope_rad,
                                       unknown_ground=unknown_ground)
    return model_energy_cost(terrain, model, params, speed_mps, model_ground=model_ground, max_slope_rad=max_slope_rad)
