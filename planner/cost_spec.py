"""CostSpec: how a map is priced — one immutable value, and the one way from it to a map's :class:`EnergyCost`.

Every answer of the planner prices a map the same way: a robot at a planning speed, a
steepest drivable slope, and either the physics presets (with a preset for cells of unknown
ground) or a saved current model (with the training grounds the map's classes are priced as),
at the mean or at a risk level. A :class:`CostSpec` holds those choices, checked once; the
entry points (:func:`planner.plan_report.plan_and_compare`, the batch, reach, mission, Monte
Carlo, replay and tour entry points) take one instead of threading them one by one, and
:meth:`CostSpec.build` is the one door to a map's edge costs (:meth:`CostSpec.at_risk` the one
to its risk-priced twin). :meth:`CostSpec.price` is the prologue every entry point shared (compile the
kernels, price the map, at the risk level, timed): its :class:`PricedMap` is the header of every
answer on a priced map (the map, the robot, the pricing, the timings), and :class:`PlanModel` what
an output says of the model that priced it.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from energy.params import RobotParams, robot_params
from terrain import TerrainMap
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

from .edge_cost import EnergyCost
from .model_cost import model_energy_cost
from .risk import check_planning_risk, risk_cost
from .warmup import warm_up_kernels

__all__ = ["CostSpec", "PricedMap", "PlanModel"]


@dataclass(frozen=True)
class PlanModel:
    """The saved current model that priced a plan's edges (route.json's ``model``).

    Attributes
    ----------
    file : str
        How the model is named (e.g. its file name).
    class_name : str
        The model's class.
    model_ground : str, mapping or None
        The ``model_ground`` it priced the map with (:func:`planner.model_energy_cost`).
    grounds : tuple of str
        The cost's ground labels.
    gives_interval : bool
        Whether the cost has a predictive interval.
    risk_q : float or None
        The quantile planned on (:func:`planner.risk_cost`), or None for the mean.
    """

    file: str
    class_name: str
    model_ground: str | Mapping[str, str] | None
    grounds: tuple[str, ...]
    gives_interval: bool
    risk_q: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """route.json's ``model`` block."""
        return {"file": self.file, "class": self.class_name, "model_ground": self.model_ground,
                "grounds": list(self.grounds), "gives_interval": self.gives_interval, "risk_q": self.risk_q,
                "objective": ("energy mean" if self.risk_q is None
                              else f"{self.risk_q:g} quantile: mean + z sd per edge")}

    def line(self) -> str:
        """The summary's ``edge costs: model ...`` line."""
        return (f"edge costs: model {self.file} ({self.class_name}) on grounds {list(self.grounds)}"
                + (f"; planned on the {self.risk_q:g} quantile of energy (each edge at mean + z sd)"
                   if self.risk_q is not None else "")
                + ("" if self.gives_interval else "; the model gives no interval"))


@dataclass(frozen=True)
class CostSpec:
    """How a map is priced: the robot, its planning speed, the steepest slope, and the physics presets or a model.

    Parameters
    ----------
    robot : str, path or RobotParams
        A robot preset name, a robot file (``.json``) or a :class:`~energy.RobotParams`
        (:func:`energy.params.robot_params`); outputs name it as given.
    speed_mps : float
        Planning speed (m/s, > 0).
    max_slope_deg : float
        Steepest drivable slope (degrees, in (0, 90)); steeper cells are blocked.
    unknown_ground : str or None
        The physics presets only: the ground preset of cells of unknown ground (class ``-1``);
        ``None`` refuses such cells. Ignored with ``model``.
    model : CurrentModel, optional
        A fitted current model (e.g. :func:`energy.load_current_model`) pricing the edges
        (:func:`planner.model_energy_cost`) instead of the physics presets.
    model_label : str, optional
        How outputs name the model (default its class name).
    model_ground : str or mapping, optional
        With ``model``: one training ground pricing every cell, or map classes priced as
        training grounds (:func:`planner.model_energy_cost`).
    risk : float, optional
        Plan on this quantile of energy (in [0.5, 1)), every edge at mean + z sd
        (:func:`planner.risk_cost`); needs a model with a predictive interval. ``None``: the mean.

    Raises
    ------
    InvalidParameterError
        A bad speed, slope or risk level (the message names the parameter).

    Examples
    --------
    >>> from terrain import flat_map
    >>> spec = CostSpec(speed_mps=0.4, max_slope_deg=15.0)
    >>> cost = spec.build(flat_map((6, 6), 1.0, ground="asphalt"))
    >>> cost.speed_mps, round(math.degrees(cost.max_slope_rad), 6), spec.at_risk(cost) is cost
    (0.4, 15.0, True)
    """

    robot: str | os.PathLike[str] | RobotParams = "husky"
    speed_mps: float = 0.5
    max_slope_deg: float = 20.0
    unknown_ground: str | None = "gravel"
    model: Any = None
    model_label: str | None = None
    model_ground: str | Mapping[str, str] | None = None
    risk: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "speed_mps", check_real("speed_mps", self.speed_mps, low=0.0, low_inclusive=False))
        object.__setattr__(self, "max_slope_deg", check_real(
            "max_slope_deg", self.max_slope_deg, low=0.0, high=90.0, low_inclusive=False, high_inclusive=False))
        if self.risk is not None:
            object.__setattr__(self, "risk", check_planning_risk(self.risk, "risk"))

    @property
    def max_slope_rad(self) -> float:
        """The steepest drivable slope (rad)."""
        return math.radians(self.max_slope_deg)

    @property
    def params(self) -> RobotParams:
        """The robot's parameters (:func:`energy.params.robot_params` of :attr:`robot`)."""
        return robot_params(self.robot)

    @property
    def preset_unknown_ground(self) -> str | None:
        """The unknown-ground preset that applies: :attr:`unknown_ground`, or None with a model."""
        return self.unknown_ground if self.model is None else None

    @property
    def model_name(self) -> str:
        """How messages and outputs name what prices the edges."""
        if self.model is None:
            return "the physics model"
        return self.model_label or type(self.model).__name__

    def build(self, terrain: TerrainMap) -> EnergyCost:
        """The map's edge costs at the mean: :meth:`EnergyCost.from_presets`, or the model's.

        Parameters
        ----------
        terrain : TerrainMap
            The map to price.

        Returns
        -------
        EnergyCost
            At the mean even with :attr:`risk` (the interval of a route is computed on it);
            :meth:`at_risk` gives the cost to plan on.

        Raises
        ------
        TerrawattError
            As :meth:`EnergyCost.from_presets` or :func:`planner.model_energy_cost`.
        """
        params = self.params  # a preset, a robot file or RobotParams: resolved once
        if self.model is None:
            return EnergyCost.from_presets(terrain, robot=params, speed_mps=self.speed_mps,
                                           max_slope_rad=self.max_slope_rad, unknown_ground=self.unknown_ground)
        return model_energy_cost(terrain, self.model, params, self.speed_mps, model_ground=self.model_ground,
                                 max_slope_rad=self.max_slope_rad)

    def needs_interval(self, cost: EnergyCost, *, also: str | None = None) -> None:
        """Raise unless ``cost`` has a predictive interval, which :attr:`risk` (and the parameter ``also``) need.

        Raises
        ------
        InvalidParameterError
            ``cost`` has no interval; the error names ``risk`` (and ``also``) as its parameters.
        """
        if cost.has_interval:
            return
        if also is None:
            level = "" if self.risk is None else f" {self.risk:g}"
            raise InvalidParameterError(
                f"risk{level} needs a model with a predictive interval; {self.model_name} gives none (its spreads are "
                f"all 0): plan without risk, or with a model that has one", parameter="risk")
        raise InvalidParameterError(f"risk and {also} model need a model with a predictive interval; "
                                    f"{self.model_name} gives none", parameter=("risk", also))

    def at_risk(self, cost: EnergyCost) -> EnergyCost:
        """The cost to plan on: ``cost`` itself without :attr:`risk`, else :func:`planner.risk_cost` at it.

        Raises
        ------
        InvalidParameterError
            :attr:`risk` with a cost that has no predictive interval.
        """
        if self.risk is None:
            return cost
        self.needs_interval(cost)
        return risk_cost(cost, self.risk)

    def plan_model(self, cost: EnergyCost) -> PlanModel | None:
        """What outputs say of the model that priced ``cost`` (route.json's ``model``); None for the presets."""
        if self.model is None:
            return None
        return PlanModel(file=self.model_name, class_name=type(self.model).__name__, model_ground=self.model_ground,
                         grounds=tuple(cost.ground_labels), gives_interval=bool(cost.has_interval),
                         risk_q=self.risk)

    def price(self, terrain: TerrainMap, *, map_label: str = "map") -> PricedMap:
        """Compile (or load) the kernels, then price ``terrain`` (:meth:`build`, :meth:`at_risk`), timed.

        The prologue of every entry point on a priced map; the kernels' compile time is kept
        apart from the map preparation.

        Returns
        -------
        PricedMap

        Raises
        ------
        TerrawattError
            As :meth:`build` and :meth:`at_risk`.
        """
        compile_s = warm_up_kernels()  # compiled once per environment, then loaded from numba's cache
        t0 = time.perf_counter()
        mean_cost = self.build(terrain)
        cost = self.at_risk(mean_cost)
        return PricedMap(self, map_label, terrain, mean_cost, cost, time.perf_counter() - t0, compile_s)


@dataclass(frozen=True, eq=False)
class PricedMap:
    """A map priced by a :class:`CostSpec`: its costs, and the header of every answer on it.

    Made by :meth:`CostSpec.price` (or, for a map read by windows and never whole, with only the
    spec, the label and the times).

    Attributes
    ----------
    spec : CostSpec
        How the map was priced.
    map_label : str
        How the map is named.
    terrain : TerrainMap or None
        The map (None when it was read by windows).
    mean_cost, cost : EnergyCost or None
        The edge costs at the mean; the ones to plan on (at the spec's risk level, else the mean).
    map_preparation_s, kernel_compile_s : float
        Seconds to price the map; to compile (or load) the kernels beforehand.
    """

    spec: CostSpec
    map_label: str
    terrain: TerrainMap | None = field(default=None, repr=False)
    mean_cost: EnergyCost | None = field(default=None, repr=False)
    cost: EnergyCost | None = field(default=None, repr=False)
    map_preparation_s: float = 0.0
    kernel_compile_s: float = 0.0

    @property
    def model(self) -> PlanModel | None:
        """What outputs say of the saved model that priced the map (with the risk level), or None for the presets."""
        return None if self.mean_cost is None else self.spec.plan_model(self.mean_cost)

    def robot_line(self) -> str:
        """``robot: NAME, speed V m/s, max slope D deg``: how the edges were priced, for a summary."""
        s = self.spec
        return f"robot: {s.robot}, speed {s.speed_mps:g} m/s, max slope {s.max_slope_deg:g} deg"

    def fields(self) -> dict[str, Any]:
        """The robot, speed and slope limit under the keys the result files give them."""
        s = self.spec
        return {"robot": s.robot, "speed_mps": s.speed_mps, "max_slope_deg": s.max_slope_deg}
