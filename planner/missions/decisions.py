"""What the navigator tells the robot: a :class:`Decision`, the forecast of what remains, a manoeuvre request.

Every call of :class:`~planner.Navigator` that takes measurements returns a
:class:`Decision` the robot's code can act on (:data:`NAVIGATOR_ACTIONS`):

- ``"continue"`` — keep driving the current route;
- ``"new_route"`` — the models changed (or the robot is off its route): drive
  :attr:`Decision.route` from here, and :attr:`Decision.reason` says why;
- ``"manoeuvre"`` — the data cannot tell a model apart: the navigator asks for the short
  drive in :attr:`Decision.manoeuvre` (the robot's code decides whether to run it, then
  feeds what it measured to ``observe_manoeuvre`` or calls ``decline_manoeuvre``);
- ``"return"`` — what remains would cross the reserve at the chosen risk, but the way back to
  the depot fits: drive :attr:`Decision.route` to the depot;
- ``"stop"`` — nothing fits above the reserve, no route exists, or the reserve was reached;
- ``"arrived"`` — at the goal (or back at the depot).

A :class:`RemainingForecast` is the energy of the rest of the mission as the navigator sees
it now: the stop-turn-go profile priced by the models in use, corrected by what this run has
shown so far (the in-run gain), with a central interval and the value at the risk level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from energy import CommandProfile
from terrawatt_base.atomic import json_finite

from ..route import Route

__all__ = ["NAVIGATOR_ACTIONS", "RemainingForecast", "ManoeuvreRequest", "Decision"]

#: What a :class:`Decision` asks the robot to do.
NAVIGATOR_ACTIONS = ("continue", "new_route", "manoeuvre", "return", "stop", "arrived")


@dataclass(frozen=True)
class RemainingForecast:
    """The energy (J) the rest of the mission will draw from the battery, with its interval.

    Attributes
    ----------
    energy_j : float
        Point forecast: the models' price of the remaining stop-turn-go profile
        (``model_energy_j``) times the in-run ``gain``.
    low_j, high_j : float
        Central ``level`` interval (J).
    level : float
        Coverage the interval is built for (e.g. 0.8).
    risk_j : float
        The value decisions are made on: the upper ``risk`` quantile, or ``energy_j`` without
        a risk level.
    risk : float or None
    model_energy_j : float
        The models' own price of what remains (no in-run correction).
    gain : float
        Measured over predicted energy of the legs driven since the models last changed,
        shrunk toward 1 (1 before any leg).
    spread : float
        Relative spread (log-ratio standard deviation) of a leg's energy about its forecast.
    legs_remaining, legs_observed : int
    soc : float
        State of charge now.
    available_j : float
        Energy above the reserve now (J).
    unseen_j : float
        The models' price of the rest on ground classes the robot has not driven yet (J): the
        part of the interval that no leg of this run has shown.
    dof : float
        Degrees of freedom of the predictive the interval and the risk quantile are read from
        (``inf``, the default: the normal distribution; the route energy interval's,
        :attr:`planner.RouteEnergyInterval.dof`).
    """

    energy_j: float
    low_j: float
    high_j: float
    level: float
    risk_j: float
    risk: float | None
    model_energy_j: float
    gain: float
    spread: float
    legs_remaining: int
    legs_observed: int
    soc: float
    available_j: float
    unseen_j: float = 0.0
    dof: float = math.inf

    @property
    def fits(self) -> bool:
        """Whether the remaining mission fits above the reserve at the risk level."""
        return self.risk_j <= self.available_j

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values (``dof`` only when finite: a Gaussian forecast's record stays as it was)."""
        return {k: json_finite(v) for k, v in vars(self).items() if k != "dof" or math.isfinite(v)}


@dataclass(frozen=True, eq=False)
class ManoeuvreRequest:
    """A short drive the navigator asks for where the driven data cannot tell a model apart.

    Attributes
    ----------
    request_id : int
    ground : str
        The map's ground class of the flagged region (a label, never its energy).
    region_cells : int
        Cells of the flagged region.
    xy_m : (float, float)
        Where it is to be driven (the robot's position: the manoeuvre is made on the spot).
    profiles : tuple of CommandProfile
        The commands, driven one after another (a straight run over speed levels, a pivot run).
    duration_s : float
    estimated_energy_j : float
        At the last leg's mean battery power.
    purpose : str
        One sentence: why it is asked for.
    """

    request_id: int
    ground: str
    region_cells: int
    xy_m: tuple[float, float]
    profiles: tuple[CommandProfile, ...]
    duration_s: float
    estimated_energy_j: float
    purpose: str

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values (the commands as lists)."""
        return {
            "request_id": self.request_id, "ground": self.ground, "region_cells": self.region_cells,
            "xy_m": [json_finite(v) for v in self.xy_m], "duration_s": json_finite(self.duration_s),
            "estimated_energy_j": json_finite(self.estimated_energy_j), "purpose": self.purpose,
            "profiles": [{"time_s": p.time_s.tolist(), "v_mps": p.v_mps.tolist(),
                          "omega_radps": p.omega_radps.tolist()} for p in self.profiles],
        }


@dataclass(frozen=True, eq=False)
class Decision:
    """What the robot should do now, and the evidence it rests on.

    Attributes
    ----------
    action : str
        One of :data:`NAVIGATOR_ACTIONS`.
    reason : str
        One sentence.
    time_s : float
        The robot's clock at the decision (the last sample it was given).
    xy_m : (float, float)
        Where the robot is.
    forecast : RemainingForecast or None
        The rest of the mission as seen now (None once it is over).
    route : Route or None
        The route to drive from here, with ``"new_route"`` and ``"return"``.
    manoeuvre : ManoeuvreRequest or None
        With ``"manoeuvre"``.
    checkpoint : int or None
        The checkpoint (leg) the decision closes, if any.
    evidence : dict
        Plain values: the flagged regions, the updates made, the leg's predicted and
        measured energy.
    """

    action: str
    reason: str
    time_s: float
    xy_m: tuple[float, float]
    forecast: RemainingForecast | None = None
    route: Route | None = None
    manoeuvre: ManoeuvreRequest | None = None
    checkpoint: int | None = None
    evidence: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values (the route as its waypoints and summary; the manoeuvre without its commands)."""
        out: dict[str, Any] = {
            "action": self.action, "reason": self.reason, "time_s": json_finite(self.time_s),
            "xy_m": [json_finite(v) for v in self.xy_m], "checkpoint": self.checkpoint,
            "forecast": None if self.forecast is None else self.forecast.to_dict(),
            "route": None if self.route is None else {"summary": self.route.summary(),
                                                      "waypoints_m": self.route.waypoints_m.tolist()},
            "manoeuvre": None if self.manoeuvre is None else {
                k: v for k, v in self.manoeuvre.to_dict().items() if k != "profiles"},
            "evidence": self.evidence,
        }
        return out
