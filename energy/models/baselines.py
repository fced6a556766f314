"""Baseline drive-current models (constant, linear, fitted physics); they never import torch.

- :class:`ConstantCurrentModel`: each side's time-averaged training current (the floor
  every model must beat).
- :class:`LinearCurrentModel`: per side ``I = a + b |v| + c |omega| + d dv/dt`` by least
  squares; fit one per ground.
- :class:`PhysicsCurrentModel`: the physics model of :class:`~energy.physics.PhysicsEnergyModel`
  with a few ground coefficients (rolling resistance, lateral friction; optionally an idle
  current) fitted to the logs by bounded non-linear least squares, and a rest level of its
  own for standing still.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import optimize

from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import check_bool, real_array
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..drivetrain import DRIVE_EFFECTS
from ..logs import InteractionLog, at_rest, log_slope_rad, rest_samples
from ..params import GroundParams, RobotParams, ground_preset, robot_preset
from ..physics import PhysicsEnergyModel
from ..power import trapezoid as _trapezoid
from .base import CurrentModel, log_currents

__all__ = [
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "PHYSICS_FIT_PARAMETERS",
    "DEFAULT_FIT_PARAMETERS",
    "ground_slots",
]


def _time_mean(logs: list[InteractionLog]) -> np.ndarray:
    charge = np.zeros(2)
    duration = 0.0
    for log in logs:
        if len(log) < 2:
            raise DataError(f"each training log needs at least 2 drive samples, got {len(log)} ({log.meta.source!r})")
        charge += _trapezoid(log_currents(log), log.time_s, axis=0)
        duration += log.duration_s
    return charge / duration


class ConstantCurrentModel(CurrentModel):
    """Predicts each side's time-averaged training current, whatever the motion.

    Attributes
    ----------
    current_a_ : numpy.ndarray, shape (2,)
        ``[left, right]`` training charge divided by training time (A).

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        ConstantCurrentModel().fit(train_logs).predict(test_log)
    """

    _param_names = ()

    def __init__(self) -> None:
        pass

    def _fit(self, logs: list[InteractionLog]) -> None:
        self.current_a_ = _time_mean(logs)

    def _predict(self, log: InteractionLog) -> np.ndarray:
        return np.tile(self.current_a_, (len(log), 1))

    def _state(self) -> dict[str, Any]:
        return {"current_a": self.current_a_.tolist()}

    def _load_state(self, state: dict[str, Any]) -> None:
        self.current_a_ = real_array("current_a", state["current_a"]).reshape(2)


def _linear_design(log: InteractionLog) -> np.ndarray:
    if len(log) < 2:
        raise DataError(f"the linear model needs at least 2 drive samples per log, got {len(log)} ({log.meta.source!r})")
    dv = np.gradient(log.v_mps, log.time_s)
    return np.column_stack([np.ones(len(log)), np.abs(log.v_mps), np.abs(log.omega_radps), dv])


class LinearCurrentModel(CurrentModel):
    """Per side, ``I = a + b |v| + c |omega| + d dv/dt`` fitted by least squares.

    ``dv/dt`` is ``numpy.gradient`` of ``v_mps`` over ``time_s`` within each log. The
    model knows nothing about the ground: fit one per ground (as the evaluation does).

    Attributes
    ----------
    coef_ : numpy.ndarray, shape (4, 2)
        Rows ``a`` (A), ``b`` (A s/m), ``c`` (A s/rad), ``d`` (A s^2/m); columns left, right.
    """

    _param_names = ()
    #: Names of the rows of ``coef_``.
    COEFFICIENTS = ("intercept_a", "speed_a_s_per_m", "omega_a_s_per_rad", "accel_a_s2_per_m")

    def __init__(self) -> None:
        pass

    def _fit(self, logs: list[InteractionLog]) -> None:
        x = np.concatenate([_linear_design(log) for log in logs])
        y = np.concatenate([log_currents(log) for log in logs])
        if x.shape[0] < x.shape[1]:
            raise DataError(f"the linear model needs at least {x.shape[1]} drive samples, got {x.shape[0]}")
        self.coef_ = np.linalg.lstsq(x, y, rcond=None)[0]

    def _predict(self, log: InteractionLog) -> np.ndarray:
        return _linear_design(log) @ self.coef_

    def _state(self) -> dict[str, Any]:
        return {"coef": self.coef_.tolist()}

    def _load_state(self, state: dict[str, Any]) -> None:
        self.coef_ = real_array("coef", state["coef"]).reshape(4, 2)


#: What :class:`PhysicsCurrentModel` fits by default: quantities the logs can tell apart.
DEFAULT_FIT_PARAMETERS: tuple[str, ...] = ("rolling_resistance_coef", "lateral_friction_coef", "rest_current_a")

#: Quantities :class:`PhysicsCurrentModel` can fit, with their bounds.
PHYSICS_FIT_PARAMETERS: dict[str, tuple[float, float]] = {
    "rolling_resistance_coef": (0.0, 2.0),
    "lateral_friction_coef": (0.0, 3.0),
    "viscous_friction_coef_s_per_m": (0.0, 5.0),
    "idle_current_a": (0.0, 20.0),
    "rest_current_a": (0.0, 20.0),
    "track_width_multiplier": (1.0, 5.0),
}


def _robot_to_plain(robot: str | RobotParams) -> Any:
    return robot if isinstance(robot, str) else {"__robot__": robot.to_plain()}


def _robot_from_plain(value: Any) -> str | RobotParams:
    return RobotParams.from_plain(value["__robot__"]) if isinstance(value, dict) else value


def _ground_to_plain(ground: str | GroundParams) -> Any:
    return ground if isinstance(ground, str) else {"__ground__": dataclasses.asdict(ground)}


def _ground_from_plain(value: Any) -> str | GroundParams:
    return GroundParams(**value["__ground__"]) if isinstance(value, dict) else value


#: Fitted quantities that are coefficients of a ground (fitted per label with a mapping of grounds).
_GROUND_COEFFICIENTS = ("rolling_resistance_coef", "lateral_friction_coef", "viscous_friction_coef_s_per_m")


def _check_ground(ground: Any) -> GroundParams | dict[str, GroundParams]:
    """One ground (preset name or parameters) or a non-empty mapping of labels to grounds."""
    def one(g: Any, where: str) -> GroundParams:
        out = ground_preset(g) if isinstance(g, str) else g
        if not isinstance(out, GroundParams):
            raise InvalidParameterError(f"{where} must be a preset name or GroundParams, got {g!r:.80}")
        return out

    if isinstance(ground, Mapping):
        if not ground:
            raise InvalidParameterError("ground must name at least one ground label when it is a mapping")
        for label in ground:
            if not isinstance(label, str) or not label.strip():
                raise InvalidParameterError(f"ground labels must be non-blank strings, got {label!r:.80}")
        return {label: one(g, f"ground[{label!r}]") for label, g in ground.items()}
    return one(ground, "ground")


def ground_slots(ground: GroundParams | Mapping[str, GroundParams],
                 log: InteractionLog) -> tuple[GroundParams | list[GroundParams], np.ndarray | None]:
    """The ground of each sample of ``log``: ``(ground, None)`` for one ground, else the list of
    grounds and each sample's index into it, by the log's ground labels.

    Raises
    ------
    DataError
        A mapping of grounds and a log without ground labels, or with a label it lacks.
    """
    if not isinstance(ground, Mapping):
        return ground, None
    labels = log.ground_labels
    if labels is None:
        raise DataError(f"a physics model with a ground per label needs ground labels in the log; "
                        f"{log.meta.source!r} has none")
    names = list(ground)
    found, index = np.unique(np.asarray(labels).astype(str), return_inverse=True)
    missing = sorted(set(found.tolist()) - set(names))
    if missing:
        raise DataError(f"{log.meta.source!r} drives on {missing!r}, which the model's grounds {names!r} lack")
    lookup = np.array([names.index(g) for g in found.tolist()], dtype=np.intp)
    return [ground[g] for g in names], lookup[index]


class PhysicsCurrentModel(CurrentModel):
    """The physics model's per-side motor current, with ground coefficients fitted to logs.

    Prediction per side: ``max(rest + idle + I_motor * sign(omega_motor), 0)`` with
    ``I_motor`` the ``motor_current_a`` of :meth:`PhysicsEnergyModel.power` for the logged
    ``v``, ``omega``, their time derivatives (``numpy.gradient``) and the slope (level
    ground, or the pitch under the logged poses on ``terrain``), where the log moves;
    standing still (:func:`energy.logs.at_rest`) the rest level ``rest_current_a_`` and, on a
    map's slope, the current of holding the robot there
    (:meth:`PhysicsEnergyModel.holding_current_a`; 0 on
    level ground): a robot at rest pushes against nothing else, whatever friction law the
    physics applies to a speed of a few mm/s read off jittery odometry. The rest level is what the current sensor
    logs with the wheels still (a sensor offset, in every sample: ``robot.rest_current_a``,
    or the mean of the logs' rest samples per side when ``"rest_current_a"`` is fitted); the
    idle current is the speed-independent current of *driving* on top of it. The current is
    taken in the direction of rotation (positive when motoring forwards *or* backwards,
    negative when back-driven), as drivers log it; the clamp at 0 models drivers that log
    motoring current only (BorealTC: never negative, exact zeros on a back-driven inner
    side); disable it with ``clip_negative=False``.

    When a log's speeds were *measured* from the wheels and ``omega`` derived with
    ``meta.track_width_m`` (as BorealTC's), the robot's ``track_width_multiplier`` is set to
    ``meta.track_width_m / robot.track_width_m`` for that log, so the model's side speeds
    are the measured wheel speeds (unless ``"track_width_multiplier"`` is fitted).

    Parameters
    ----------
    robot : str or RobotParams
        Robot preset name (default ``"husky"``) or parameters.
    ground : str, GroundParams or mapping of str to (str or GroundParams)
        Starting ground (preset name or parameters); the fitted coefficients replace its
        values, the others (e.g. slip coefficients) are kept. A mapping gives each ground
        label of the logs (``InteractionLog.ground_labels``, per sample) its own ground, as
        a planner prices each cell by its ground: a log with a label the mapping lacks is a
        ``DataError``; fitted ground coefficients are then fitted per label
        (``fitted_["grass.rolling_resistance_coef"]``).
    fit_parameters : tuple of str
        Names from :data:`PHYSICS_FIT_PARAMETERS` to fit (default
        :data:`DEFAULT_FIT_PARAMETERS`: rolling resistance, lateral friction, rest level; not
        the idle current, which on level ground is a constant current while moving just as
        rolling resistance is, so a fit of both cannot tell them apart and the idle current
        takes what is physics — and then a payload, which scales rolling resistance, can no
        longer be told from a current gain). ``"rest_current_a"`` is fitted apart,
        in closed form: the mean current of each side over the rest samples (a side keeps
        ``robot.rest_current_a`` when the logs never stand still); the others by least
        squares on the moving samples. ``()``: the model as given (``fit`` only checks
        the logs).
    effects : tuple of str or None
        Physics effects (``None``: all drive effects, i.e. :data:`EFFECTS` without the
        electronics ``"sensor"`` and ``"control"``, which draw no motor current).
    clip_negative : bool
        Clamp predicted currents at 0.
    terrain : TerrainMap, optional
        The map the logs drove on: the slope under their poses enters the physics (every log
        needs poses), as it does when planning on that map; without it, level ground. Not
        stored in the model file, which records that the model needs one (``on_map_``): a
        loaded model predicts only once given its map again with :meth:`with_terrain`.

    Attributes
    ----------
    ground_ : GroundParams or None
        Ground with the fitted coefficients (None for a mapping of grounds).
    grounds_ : dict of str to GroundParams
        Per-label grounds with their fitted coefficients (empty for a single ground).
    robot_ : RobotParams
        Robot (with the fitted ``track_width_multiplier`` when fitted).
    idle_current_a_ : float
        Current on top of the rest level while moving (A).
    rest_current_a_ : numpy.ndarray, shape (2,)
        ``[left, right]`` rest level (A).
    fitted_ : dict of str to float
        The fitted values by name.
    cost_ : float
        Final mean squared residual (A^2).
    """

    _param_names = ("robot", "ground", "fit_parameters", "effects", "clip_negative", "terrain")

    def __init__(self, robot: str | RobotParams = "husky",
                 ground: str | GroundParams | Mapping[str, str | GroundParams] = "asphalt",
                 fit_parameters: Sequence[str] = DEFAULT_FIT_PARAMETERS,
                 effects: Sequence[str] | None = None, clip_negative: bool = True,
                 terrain: TerrainMap | None = None) -> None:
        self.robot = robot
        self.ground = ground
        self.fit_parameters = fit_parameters
        self.effects = effects
        self.clip_negative = clip_negative
        self.terrain = terrain

    def _check(self) -> tuple[RobotParams, GroundParams | dict[str, GroundParams], tuple[str, ...],
                              PhysicsEnergyModel]:
        robot = robot_preset(self.robot) if isinstance(self.robot, str) else self.robot
        if not isinstance(robot, RobotParams):
            raise InvalidParameterError(f"robot must be a preset name or RobotParams, got {self.robot!r:.80}")
        ground = _check_ground(self.ground)
        if self.terrain is not None and not isinstance(self.terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap or None, got {type(self.terrain).__name__!r}")
        if isinstance(self.fit_parameters, str):
            raise InvalidParameterError(f"fit_parameters must be a sequence of names, not a string: {self.fit_parameters!r}")
        names = tuple(self.fit_parameters)
        for n in names:
            if n not in PHYSICS_FIT_PARAMETERS:
                raise UnknownNameError(f"fit parameter {n!r} is unknown; expected names from {sorted(PHYSICS_FIT_PARAMETERS)!r}")
        if len(set(names)) != len(names):
            raise InvalidParameterError(f"fit_parameters has duplicates: {names!r}")
        check_bool("clip_negative", self.clip_negative)
        effects = DRIVE_EFFECTS if self.effects is None else tuple(self.effects)
        model = PhysicsEnergyModel(robot, effects)
        return robot, ground, names, model

    def _log_robot(self, robot: RobotParams, log: InteractionLog, fitted_chi: bool) -> RobotParams:
        if fitted_chi or log.meta.velocity_source != "measured" or log.meta.track_width_m is None:
            return robot
        chi = log.meta.track_width_m / robot.track_width_m
        if chi < 1.0:
            return robot  # a narrower derivation track than the robot's: keep the robot's own chi
        return dataclasses.replace(robot, track_width_multiplier=chi)

    @staticmethod
    def _inputs(log: InteractionLog) -> tuple[np.ndarray, ...]:
        if len(log) < 2:
            raise DataError(f"the physics model needs at least 2 drive samples per log, got {len(log)} ({log.meta.source!r})")
        return (log.v_mps, log.omega_radps, np.gradient(log.v_mps, log.time_s), np.gradient(log.omega_radps, log.time_s))

    def _place(self, ground: GroundParams | dict[str, GroundParams],
                log: InteractionLog) -> tuple[np.ndarray | None, np.ndarray | float]:
        """Where ``log`` drives, whatever the coefficients: each sample's ground slot and the slope under it."""
        return ground_slots(ground, log)[1], 0.0 if self.terrain is None else log_slope_rad(self.terrain, log)

    def _current(self, robot: RobotParams, ground: GroundParams | dict[str, GroundParams], idle_a: float,
                 effects: tuple[str, ...], log: InteractionLog, fitted_chi: bool, rest_a: np.ndarray,
                 place: tuple[np.ndarray | None, np.ndarray | float] | None = None) -> np.ndarray:
        model = PhysicsEnergyModel(self._log_robot(robot, log, fitted_chi), effects)
        v, w, a, alpha = self._inputs(log)
        index, slope = self._place(ground, log) if place is None else place
        grounds = list(ground.values()) if isinstance(ground, dict) else ground
        res = model.power(v, w, grounds, accel_mps2=a, alpha_radps2=alpha, slope_rad=slope, time_s=log.time_s,
                          ground_index=index)
        i_m = res.motor_current_a
        # current in the direction of rotation: > 0 motoring (either way round), < 0 back-driven
        sign = np.sign(res.motor_speed_radps)
        motoring = np.where(sign != 0, i_m * sign, np.abs(i_m))
        rest = at_rest(v, w, a, alpha)
        holding = model.holding_current_a(grounds, np.where(rest, slope, 0.0), ground_index=index)  # where it stands
        cur = rest_a + np.where(rest[:, None], holding, idle_a + motoring)
        return np.maximum(cur, 0.0) if self.clip_negative else cur

    @staticmethod
    def _rest_level(robot: RobotParams, logs: list[InteractionLog], fit: bool) -> np.ndarray:
        """Per-side rest level: the mean of the logs' rest samples (``fit``, sides with any), else the robot's."""
        level = np.full(2, float(robot.rest_current_a))
        if not fit:
            return level
        rest = np.concatenate([log_currents(log)[rest_samples(log)] for log in logs])
        if rest.shape[0]:
            level = rest.mean(axis=0)
        return level

    @staticmethod
    def _fit_names(names: tuple[str, ...], ground: GroundParams | dict[str, GroundParams]) -> tuple[str, ...]:
        """The fitted quantities: with a mapping of grounds, each ground coefficient once per label."""
        if not isinstance(ground, dict):
            return names
        return tuple(f"{g}.{n}" if n in _GROUND_COEFFICIENTS else n
                     for n in names for g in (ground if n in _GROUND_COEFFICIENTS else (None,)))

    @staticmethod
    def _apply(robot: RobotParams, ground: GroundParams | dict[str, GroundParams], theta: np.ndarray,
               names: tuple[str, ...]) -> tuple[RobotParams, GroundParams | dict[str, GroundParams], float]:
        values = dict(zip(names, theta.tolist()))
        idle = values.pop("idle_current_a", 0.0)
        chi = values.pop("track_width_multiplier", None)
        if chi is not None:
            robot = dataclasses.replace(robot, track_width_multiplier=chi)
        if isinstance(ground, dict):
            per: dict[str, dict[str, float]] = {}
            for key, value in values.items():
                label, coef = key.rsplit(".", 1)
                per.setdefault(label, {})[coef] = value
            ground = {g: (p.replace(**per[g]) if g in per else p) for g, p in ground.items()}
        elif values:
            ground = ground.replace(**values)
        return robot, ground, idle

    @staticmethod
    def _start(name: str, robot: RobotParams, ground: GroundParams | dict[str, GroundParams]) -> float:
        coef = name.rsplit(".", 1)[-1]
        g = ground[name.rsplit(".", 1)[0]] if isinstance(ground, dict) and coef in _GROUND_COEFFICIENTS else ground
        if coef == "idle_current_a":
            x0 = 0.5
        elif coef == "track_width_multiplier":
            x0 = robot.track_width_multiplier
        elif coef == "lateral_friction_coef":
            x0 = g.effective_lateral_friction_coef
        else:
            x0 = getattr(g, coef)
        lo, hi = PHYSICS_FIT_PARAMETERS[coef]
        return min(max(x0, lo), hi)

    def _check_params(self) -> tuple[RobotParams, GroundParams | dict[str, GroundParams], tuple[str, ...],
                                     PhysicsEnergyModel]:
        return self._check()

    def _fit(self, logs: list[InteractionLog]) -> None:
        robot, ground, all_names, model = self._check()
        effects = model.effects
        places = [self._place(ground, log) for log in logs]  # every label known before any work, computed once
        rest_a = self._rest_level(robot, logs, "rest_current_a" in all_names)
        names = self._fit_names(tuple(n for n in all_names if n != "rest_current_a"), ground)
        truth = np.concatenate([log_currents(log) for log in logs]).ravel()
        fitted_chi = "track_width_multiplier" in names
        start = [self._start(n, robot, ground) for n in names]
        lower = np.array([PHYSICS_FIT_PARAMETERS[n.rsplit(".", 1)[-1]][0] for n in names])
        upper = np.array([PHYSICS_FIT_PARAMETERS[n.rsplit(".", 1)[-1]][1] for n in names])

        def residual(theta: np.ndarray) -> np.ndarray:
            r, g, idle = self._apply(robot, ground, theta, names)
            pred = np.concatenate([self._current(r, g, idle, effects, log, fitted_chi, rest_a, place)
                                   for log, place in zip(logs, places)]).ravel()
            return pred - truth

        if names:
            sol = optimize.least_squares(residual, np.array(start, dtype=np.float64), bounds=(lower, upper),
                                         x_scale="jac", diff_step=1e-3)
            theta = sol.x
        else:
            theta = np.zeros(0)
        r, g, idle = self._apply(robot, ground, theta, names)
        self.robot_ = r
        self.ground_ = None if isinstance(g, dict) else g
        self.grounds_ = dict(g) if isinstance(g, dict) else {}
        self.idle_current_a_ = float(idle)
        self.rest_current_a_ = rest_a
        self.fitted_ = dict(zip(names, (float(x) for x in theta)))
        if "rest_current_a" in all_names:
            self.fitted_.update(rest_left_a=float(rest_a[0]), rest_right_a=float(rest_a[1]))
        self.cost_ = float(np.mean(residual(theta) ** 2))
        self.effects_ = effects
        self.on_map_ = self.terrain is not None

    @property
    def fitted_ground(self) -> GroundParams | dict[str, GroundParams]:
        """The fitted ground: one GroundParams, or the per-label mapping."""
        self._check_fitted()
        return self.ground_ if self.ground_ is not None else self.grounds_

    def with_terrain(self, terrain: TerrainMap) -> PhysicsCurrentModel:
        """This fitted model on ``terrain``: the slope under the logged poses enters its physics (after loading)."""
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        self._check_fitted()
        out = copy.copy(self)
        out.terrain = terrain
        out.on_map_ = True
        return out

    def check_map(self) -> None:
        """Raise :class:`DataError` when the model drives a map's slope (``on_map_``) but holds no map (loaded)."""
        self._check_fitted()
        if self.on_map_ and self.terrain is None:
            raise DataError("this physics model drives the slope of the map it was fitted on, which a model file does "
                            "not store; give the map again with with_terrain(tmap)")

    def _predict(self, log: InteractionLog) -> np.ndarray:
        self.check_map()
        return self._current(self.robot_, self.fitted_ground, self.idle_current_a_, self.effects_, log,
                             "track_width_multiplier" in self.fitted_, self.rest_current_a_)

    def _params_to_plain(self) -> dict[str, Any]:
        ground = ({"__grounds__": {g: _ground_to_plain(p) for g, p in self.ground.items()}}
                  if isinstance(self.ground, Mapping) else _ground_to_plain(self.ground))
        return {
            "robot": _robot_to_plain(self.robot),
            "ground": ground,
            "fit_parameters": list(self.fit_parameters),
            "effects": None if self.effects is None else list(self.effects),
            "clip_negative": self.clip_negative,
            "terrain": None,  # a map is not stored in a model file (with_terrain after loading)
        }

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        p = dict(params)
        p["robot"] = _robot_from_plain(p["robot"])
        g = p["ground"]
        if isinstance(g, dict) and "__grounds__" in g:
            if not isinstance(g["__grounds__"], dict):
                raise ValueError("'__grounds__' must map ground labels to grounds")
            p["ground"] = {str(k): _ground_from_plain(v) for k, v in g["__grounds__"].items()}
        else:
            p["ground"] = _ground_from_plain(g)
        p["fit_parameters"] = tuple(p["fit_parameters"])
        if p.get("effects") is not None:
            p["effects"] = tuple(p["effects"])
        if p.get("terrain") is not None:
            raise ValueError("a model file stores no map: 'terrain' must be null")
        p["terrain"] = None
        return p

    def _state(self) -> dict[str, Any]:
        state = {
            "robot": self.robot_.to_plain(),
            "ground": None if self.ground_ is None else dataclasses.asdict(self.ground_),
            "idle_current_a": self.idle_current_a_,
            "rest_current_a": self.rest_current_a_.tolist(),
            "fitted": dict(self.fitted_),
            "cost": self.cost_,
            "effects": list(self.effects_),
            "on_map": bool(self.on_map_),
        }
        if self.grounds_:
            state["grounds"] = {g: dataclasses.asdict(p) for g, p in self.grounds_.items()}
        return state

    def _load_state(self, state: dict[str, Any]) -> None:
        self.robot_ = _robot_from_plain({"__robot__": state["robot"]})
        grounds = state.get("grounds")
        if grounds is not None:
            if not isinstance(grounds, dict) or not grounds:
                raise ValueError("'grounds' must map ground labels to grounds")
            self.grounds_ = {str(k): GroundParams(**v) for k, v in grounds.items()}
            self.ground_ = None
        else:
            self.ground_ = GroundParams(**state["ground"])
            self.grounds_ = {}
        self.idle_current_a_ = float(state["idle_current_a"])
        if "rest_current_a" in state:
            self.rest_current_a_ = real_array("rest_current_a", state["rest_current_a"]).reshape(2)
        else:  # a file from before the rest level: its idle current was the level at rest and the base of driving
            self.rest_current_a_ = np.full(2, self.idle_current_a_)
            self.idle_current_a_ = 0.0
        self.fitted_ = {str(k): float(v) for k, v in state["fitted"].items()}
        self.cost_ = float(state["cost"])
        self.effects_ = tuple(str(e) for e in state["effects"])
        on_map = state.get("on_map", False)  # files from before the map's slope: level ground
        if not isinstance(on_map, bool):
            raise ValueError("'on_map' must be true or false")
        self.on_map_ = on_map
        PhysicsEnergyModel(self.robot_, self.effects_)  # validates the effect names
        if (not all(math.isfinite(v) for v in self.fitted_.values()) or not math.isfinite(self.idle_current_a_)
                or not np.all(np.isfinite(self.rest_current_a_))):
            raise ValueError("non-finite fitted coefficient")
