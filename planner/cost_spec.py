"""CostSpec: how a map is priced — one immutable value, and the one way from it to a map's :class:`EnergyCost`.

Every answer of the planner prices a map the same way: a robot at a planning speed, a
steepest drivable slope, and either the robot's physics model over the map's grounds (the
ground presets the classes are named after, or parameters given per class; a preset for cells
of unknown ground), another :class:`energy.EnergyModel` over given grounds, or a saved current
model (with the training grounds the map's classes are priced as), at the mean or at a risk
level. A :class:`CostSpec` holds those choices, checked once; the
entry points (:func:`planner.plan_report.plan_and_compare`, the batch, reach, mission, Monte
Carlo, replay and tour entry points) take one instead of threading them one by one, and
:meth:`CostSpec.build` is the one door to a map's edge costs (:meth:`CostSpec.at_risk` the one
to its risk-priced twin: the same map on its tables' quantile, :meth:`CostTables.at_quantile`).
:meth:`CostSpec.price` is the prologue every entry point shared (compile the kernels, price the
map, at the risk level, timed): its :class:`PricedMap` is the header of every
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

import numpy as np

from energy import GROUND_PRESETS, EnergyModel, PhysicsEnergyModel, ground_preset
from energy.params import RobotParams, robot_params
from terrain import TerrainMap
from terrain.terrain_map import UNKNOWN_GROUND
from terrawatt_base.checks import check_instance, check_real
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .edge_cost import EnergyCost
from .model_cost import model_energy_cost
from .tables import (
    DEFAULT_GRADE_SAMPLES,
    DEFAULT_TURN_SAMPLES,
    CostTables,
    check_planning_risk,
    ground_table_rows,
    tabulate,
)
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
        The ``model_ground`` it priced the map with (:func:`planner.model_cost.model_energy_cost`).
    grounds : tuple of str
        The cost's ground labels.
    gives_interval : bool
        Whether the cost has a predictive interval.
    risk_q : float or None
        The quantile planned on (:meth:`CostSpec.at_risk`), or None for the mean.
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
        (:func:`energy.params.robot_params`); outputs name it as given. Its physics model prices
        the map unless ``energy_model`` or ``model`` is given; its battery voltage and turn rate
        (for charge and turn durations) serve an ``energy_model`` that carries no robot of its own.
    speed_mps : float
        Planning speed (m/s, > 0).
    max_slope_deg : float
        Steepest drivable slope (degrees, in (0, 90)); steeper cells are blocked.
    unknown_ground : str, ground parameters or None
        Cells of unknown ground (class ``-1``): a ground preset's name or
        :class:`~energy.GroundParams` for the physics model; the parameters an ``energy_model``
        takes for a ground (a preset's name is refused there, where the map has such cells);
        ``None`` refuses such cells. Ignored with ``model``.
    grounds : mapping, optional
        The ground parameters of the map's classes, keyed by class name
        (``terrain.ground_names``) or class id (e.g. ``{"asphalt": ground_preset("asphalt"),
        1: wet}``); every class of the map needs one, extra keys are ignored. Default: the
        ground preset each class is named after. Not with ``model``.
    energy_model : energy.EnergyModel, optional
        An energy model to tabulate over ``grounds`` (``energy_per_metre_j`` and
        ``turn_energy_j``) instead of the robot's :class:`energy.PhysicsEnergyModel`; ``grounds``
        is then required. Not with ``model``.
    model : CurrentModel, optional
        A fitted current model (e.g. :func:`energy.load_current_model`) pricing the edges
        (:func:`planner.model_cost.model_energy_cost`) instead of the physics presets.
    model_label : str, optional
        How outputs name the model (default its class name).
    model_ground : str or mapping, optional
        With ``model``: one training ground pricing every cell, or map classes priced as
        training grounds (:func:`planner.model_cost.model_energy_cost`).
    risk : float, optional
        Plan on this quantile of energy (in [0.5, 1)), every edge at mean + z sd
        (:meth:`at_risk`); needs a model with a predictive interval. ``None``: the mean.

    Raises
    ------
    InvalidParameterError
        A bad speed, slope or risk level (the message names the parameter); ``model`` with
        ``grounds`` or ``energy_model``; ``energy_model`` without ``grounds`` or not an
        :class:`energy.EnergyModel`.

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
    unknown_ground: Any = "gravel"
    grounds: Mapping[str, Any] | Mapping[int, Any] | None = None
    energy_model: Any = None
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
        if self.model is not None and (self.grounds is not None or self.energy_model is not None):
            raise InvalidParameterError("a current model prices the map by its training grounds (model_ground); "
                                        "grounds and energy_model are for an energy model", parameter="model")
        if self.energy_model is not None:
            if not isinstance(self.energy_model, EnergyModel):
                raise InvalidParameterError(
                    f"energy_model must be an energy.EnergyModel (energy_per_metre_j and turn_energy_j), got "
                    f"{type(self.energy_model).__name__!r}", parameter="energy_model")
            if self.grounds is None:
                raise InvalidParameterError("energy_model needs the ground parameters of the map's classes (grounds)",
                                            parameter="grounds")
        if self.grounds is not None:
            if not isinstance(self.grounds, Mapping):
                raise InvalidParameterError(f"grounds must be a mapping of ground class (name or id) to parameters, "
                                            f"got {type(self.grounds).__name__!r}", parameter="grounds")
            object.__setattr__(self, "grounds", dict(self.grounds))  # the spec's own copy (a proxy would not pickle)

    @classmethod
    def given(cls, pricing: CostSpec | None) -> CostSpec:
        """An entry point's ``pricing``: the default ``CostSpec()`` for None, else ``pricing`` itself, checked.

        Raises
        ------
        InvalidParameterError
            ``pricing`` neither None nor a :class:`CostSpec` (the error names ``pricing``).

        Examples
        --------
        >>> CostSpec.given(None) == CostSpec()
        True
        """
        return cls() if pricing is None else check_instance("pricing", pricing, cls)

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
        """The map's edge costs at the mean: the energy model tabulated over the map's grounds, or the current model's.

        The energy model (the robot's physics model, or :attr:`energy_model`) is asked once
        per ground class of the map for its energy per metre at every grade of the table and
        its turn energy at every angle (:func:`planner.tables.tabulate`); a current model is
        priced by :func:`planner.model_cost.model_energy_cost`.

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
        UnknownNameError
            A ground class of the map without parameters (named after no preset, when
            :attr:`grounds` is not given: the message lists the presets); an unknown robot
            or unknown-ground preset.
        InvalidParameterError
            ``terrain`` not a :class:`~terrain.TerrainMap`; unknown-ground cells with
            :attr:`unknown_ground` None; an energy model returning negative, non-finite or
            wrongly shaped energies, or without a battery voltage and turn rate of its own or
            the robot's.
        TerrawattError
            As :func:`planner.model_cost.model_energy_cost` with a current model.
        """
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}",
                                        parameter="terrain")
        params = self.params  # a preset, a robot file or RobotParams: resolved once
        if self.model is not None:
            return model_energy_cost(terrain, self.model, params, self.speed_mps, model_ground=self.model_ground,
                                     max_slope_rad=self.max_slope_rad)
        model = PhysicsEnergyModel(params) if self.energy_model is None else self.energy_model
        physics = isinstance(model, PhysicsEnergyModel)
        grounds = _preset_grounds(terrain) if self.grounds is None else self.grounds
        unknown = self.unknown_ground
        if isinstance(unknown, str):  # a preset's name: the physics model's ground
            if not physics and np.any(np.asarray(terrain.ground) == UNKNOWN_GROUND):
                raise InvalidParameterError(
                    f"unknown_ground {unknown!r} names a ground preset of the physics model; give the energy model's "
                    f"own parameters for the map's cells of unknown ground", parameter="unknown_ground")
            unknown = ground_preset(unknown) if physics else None
        return _tabulated_cost(terrain, model, grounds, unknown, self.speed_mps, self.max_slope_rad, params)

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
        """The cost to plan on: ``cost`` itself without :attr:`risk`, else the same map on its tables at :attr:`risk`.

        Every entry of the tables at its quantile (:meth:`planner.tables.CostTables.at_quantile`), laid on
        the map's geometry (:meth:`EnergyCost.with_tables`); the spreads are kept, so a route's
        interval can be read from either cost.

        Raises
        ------
        InvalidParameterError
            :attr:`risk` with a cost that has no predictive interval.
        """
        if self.risk is None:
            return cost
        self.needs_interval(cost)
        return cost.with_tables(cost.tables.at_quantile(self.risk))

    def plan_model(self, cost: EnergyCost) -> PlanModel | None:
        """What outputs say of the model that priced ``cost`` (route.json's ``model``); None for the presets."""
        if self.model is None:
            return None
        return PlanModel(file=self.model_name, class_name=type(self.model).__name__, model_ground=self.model_ground,
                         grounds=tuple(cost.tables.ground_labels), gives_interval=bool(cost.has_interval),
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


def _preset_grounds(terrain: TerrainMap) -> dict[int, Any]:
    """The ground preset of every class of the map, by class id (each class named after a preset)."""
    grounds = {}
    for gid, name in terrain.ground_names.items():
        if name not in GROUND_PRESETS:
            raise UnknownNameError(
                f"ground class {gid} of the map is named {name!r}, which has no preset; "
                f"known grounds: {sorted(GROUND_PRESETS)!r}", parameter="grounds")
        grounds[gid] = ground_preset(name)
    return grounds


def _robot_figure(model: Any, robot: RobotParams, name: str) -> float:
    """The model's (or its robot's) value of ``name``, else the spec's robot's."""
    for owner in (model, getattr(model, "robot", None), robot):
        value = getattr(owner, name, None)
        if value is not None:
            return float(value)
    raise InvalidParameterError(f"neither the energy model nor the robot gives {name}", parameter="energy_model")


def _tabulated_cost(terrain: TerrainMap, model: Any, grounds: Mapping[Any, Any], unknown_ground: Any,
                    speed_mps: float, max_slope_rad: float, robot: RobotParams) -> EnergyCost:
    """An energy model tabulated over the map's ground classes: the map-preparation step.

    ``model.energy_per_metre_j(speed_mps, grades, ground)`` is called once per ground with
    every grade of the table, and ``model.turn_energy_j(angles, ground)`` once per ground over
    ``[0, pi]`` (turns are priced on level ground: a pivot's extra load on a slope is not in the
    table). The physics model prices its turn table as the stop-turn-go drive it is driven with
    (:func:`planner.tables.stop_turn_go_rows`: the stop, the ramped pivot and the start again, at
    the cost's turn rate), so the edges price what the robot drives. The model's energy is per
    metre *travelled*; the table stores it per *horizontal* (map) metre, i.e. times
    ``sqrt(1 + grade**2)``. A model may return ``+inf`` for grades a
    ground cannot be driven at; segments meeting such a grade in their direction of travel are
    then invalid in that direction only.
    """
    t0 = time.perf_counter()
    voltage = _robot_figure(model, robot, "battery_voltage_v")
    turn_rate = _robot_figure(model, robot, "turn_rate_radps")
    rows, params_rows, labels = ground_table_rows(terrain, grounds, unknown_ground)
    physics = isinstance(model, PhysicsEnergyModel)
    grade_table, turn_table = tabulate(model, speed_mps, params_rows, labels, max_slope_rad=max_slope_rad,
                                       grade_samples=DEFAULT_GRADE_SAMPLES, turn_samples=DEFAULT_TURN_SAMPLES,
                                       stop_turn_go_rate_radps=turn_rate if physics else None)
    cost = EnergyCost(terrain, rows, CostTables(grade_table, turn_table, tuple(labels)), speed_mps=speed_mps,
                      max_slope_rad=max_slope_rad, battery_voltage_v=voltage, turn_rate_radps=turn_rate)
    if physics:
        cost.physics_model, cost.ground_params = model, tuple(params_rows)
    cost.prep_time_s = time.perf_counter() - t0
    return cost


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
