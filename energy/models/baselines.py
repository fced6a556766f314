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

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import optimize

from terrawatt_base.checks import check_bool, real_array
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..logs import InteractionLog, at_rest, rest_samples
from ..params import GroundParams, MotorParams, RobotParams, ground_preset, robot_preset
from ..physics import EFFECTS, PhysicsEnergyModel
from .base import CurrentModel, log_currents

__all__ = [
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "PHYSICS_FIT_PARAMETERS",
    "DEFAULT_FIT_PARAMETERS",
]

_trapezoid = getattr(np, "trapezoid", None) or np.trapz


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
_DRIVE_EFFECTS = tuple(e for e in EFFECTS if e not in ("sensor", "control"))


def _robot_to_plain(robot: str | RobotParams) -> Any:
    if isinstance(robot, str):
        return robot
    d = dataclasses.asdict(robot)
    return {"__robot__": d}


def _robot_from_plain(value: Any) -> str | RobotParams:
    if isinstance(value, dict):
        d = dict(value["__robot__"])
        d["motor"] = MotorParams(**d["motor"])
        return RobotParams(**d)
    return value


def _ground_to_plain(ground: str | GroundParams) -> Any:
    return ground if isinstance(ground, str) else {"__ground__": dataclasses.asdict(ground)}


def _ground_from_plain(value: Any) -> str | GroundParams:
    return GroundParams(**value["__ground__"]) if isinstance(value, dict) else value


class PhysicsCurrentModel(CurrentModel):
    """The physics model's per-side motor current, with ground coefficients fitted to logs.

    Prediction per side: ``max(rest + idle + I_motor * sign(omega_motor), 0)`` with
    ``I_motor`` the ``motor_current_a`` of :meth:`PhysicsEnergyModel.power` for the logged
    ``v``, ``omega``, their time derivatives (``numpy.gradient``) and zero slope, where the
    log moves; standing still (:func:`energy.logs.at_rest`) the rest level
    ``rest_current_a_`` alone: a robot at rest pushes against nothing, whatever friction
    law the physics applies to a speed of a few mm/s read off jittery odometry. The rest
    level is what the current sensor logs with the wheels still (a sensor offset, in every
    sample: ``robot.rest_current_a``, or the mean of the logs' rest samples per side when
    ``"rest_current_a"`` is fitted); the idle current is the speed-independent current of
    *driving* on top of it. The current is taken in the direction of rotation (positive when motoring forwards *or*
    backwards, negative when back-driven), as drivers log it; the clamp at 0 models drivers
    that log motoring current only (BorealTC: never negative, exact zeros on a back-driven
    inner side); disable it with ``clip_negative=False``.

    When a log's speeds were *measured* from the wheels and ``omega`` derived with
    ``meta.track_width_m`` (as BorealTC's), the robot's ``track_width_multiplier`` is set to
    ``meta.track_width_m / robot.track_width_m`` for that log, so the model's side speeds
    are the measured wheel speeds (unless ``"track_width_multiplier"`` is fitted).

    Parameters
    ----------
    robot : str or RobotParams
        Robot preset name (default ``"husky"``) or parameters.
    ground : str or GroundParams
        Starting ground (preset name or parameters); the fitted coefficients replace its
        values, the others (e.g. slip coefficients) are kept.
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

    Attributes
    ----------
    ground_ : GroundParams
        Ground with the fitted coefficients.
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

    _param_names = ("robot", "ground", "fit_parameters", "effects", "clip_negative")

    def __init__(self, robot: str | RobotParams = "husky", ground: str | GroundParams = "asphalt",
                 fit_parameters: Sequence[str] = DEFAULT_FIT_PARAMETERS,
                 effects: Sequence[str] | None = None, clip_negative: bool = True) -> None:
        self.robot = robot
        self.ground = ground
        self.fit_parameters = fit_parameters
        self.effects = effects
        self.clip_negative = clip_negative

    def _check(self) -> tuple[RobotParams, GroundParams, tuple[str, ...], PhysicsEnergyModel]:
        robot = robot_preset(self.robot) if isinstance(self.robot, str) else self.robot
        if not isinstance(robot, RobotParams):
            raise InvalidParameterError(f"robot must be a preset name or RobotParams, got {self.robot!r:.80}")
        ground = ground_preset(self.ground) if isinstance(self.ground, str) else self.ground
        if not isinstance(ground, GroundParams):
            raise InvalidParameterError(f"ground must be a preset name or GroundParams, got {self.ground!r:.80}")
        if isinstance(self.fit_parameters, str):
            raise InvalidParameterError(f"fit_parameters must be a sequence of names, not a string: {self.fit_parameters!r}")
        names = tuple(self.fit_parameters)
        for n in names:
            if n not in PHYSICS_FIT_PARAMETERS:
                raise UnknownNameError(f"fit parameter {n!r} is unknown; expected names from {sorted(PHYSICS_FIT_PARAMETERS)!r}")
        if len(set(names)) != len(names):
            raise InvalidParameterError(f"fit_parameters has duplicates: {names!r}")
        check_bool("clip_negative", self.clip_negative)
        effects = _DRIVE_EFFECTS if self.effects is None else tuple(self.effects)
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

    def _current(self, robot: RobotParams, ground: GroundParams, idle_a: float, effects: tuple[str, ...],
                 log: InteractionLog, fitted_chi: bool, rest_a: np.ndarray) -> np.ndarray:
        model = PhysicsEnergyModel(self._log_robot(robot, log, fitted_chi), effects)
        v, w, a, alpha = self._inputs(log)
        res = model.power(v, w, ground, accel_mps2=a, alpha_radps2=alpha, time_s=log.time_s)
        i_m = res.motor_current_a
        # current in the direction of rotation: > 0 motoring (either way round), < 0 back-driven
        sign = np.sign(res.motor_speed_radps)
        motoring = np.where(sign != 0, i_m * sign, np.abs(i_m))
        cur = rest_a + np.where(at_rest(v, w, a, alpha)[:, None], 0.0, idle_a + motoring)
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

    def _apply(self, robot: RobotParams, ground: GroundParams, theta: np.ndarray,
               names: tuple[str, ...]) -> tuple[RobotParams, GroundParams, float]:
        values = dict(zip(names, theta.tolist()))
        values.pop("rest_current_a", None)  # fitted apart (closed form)
        idle = values.pop("idle_current_a", 0.0)
        chi = values.pop("track_width_multiplier", None)
        if chi is not None:
            robot = dataclasses.replace(robot, track_width_multiplier=chi)
        if values:
            ground = ground.replace(**values)
        return robot, ground, idle

    def _check_params(self) -> tuple[RobotParams, GroundParams, tuple[str, ...], PhysicsEnergyModel]:
        return self._check()

    def _fit(self, logs: list[InteractionLog]) -> None:
        robot, ground, all_names, model = self._check()
        effects = model.effects
        rest_a = self._rest_level(robot, logs, "rest_current_a" in all_names)
        names = tuple(n for n in all_names if n != "rest_current_a")
        truth = np.concatenate([log_currents(log) for log in logs]).ravel()
        fitted_chi = "track_width_multiplier" in names
        start = []
        for n in names:
            lo, hi = PHYSICS_FIT_PARAMETERS[n]
            if n == "idle_current_a":
                x0 = 0.5
            elif n == "track_width_multiplier":
                x0 = robot.track_width_multiplier
            elif n == "lateral_friction_coef":
                x0 = ground.effective_lateral_friction_coef
            else:
                x0 = getattr(ground, n)
            start.append(min(max(x0, lo), hi))
        lower = np.array([PHYSICS_FIT_PARAMETERS[n][0] for n in names])
        upper = np.array([PHYSICS_FIT_PARAMETERS[n][1] for n in names])

        def residual(theta: np.ndarray) -> np.ndarray:
            r, g, idle = self._apply(robot, ground, theta, names)
            pred = np.concatenate([self._current(r, g, idle, effects, log, fitted_chi, rest_a)
                                   for log in logs]).ravel()
            return pred - truth

        if names:
            sol = optimize.least_squares(residual, np.array(start, dtype=np.float64), bounds=(lower, upper),
                                         x_scale="jac", diff_step=1e-3)
            theta = sol.x
        else:
            theta = np.zeros(0)
        r, g, idle = self._apply(robot, ground, theta, names)
        self.robot_ = r
        self.ground_ = g
        self.idle_current_a_ = float(idle)
        self.rest_current_a_ = rest_a
        self.fitted_ = dict(zip(names, (float(x) for x in theta)))
        if "rest_current_a" in all_names:
            self.fitted_.update(rest_left_a=float(rest_a[0]), rest_right_a=float(rest_a[1]))
        self.cost_ = float(np.mean(residual(theta) ** 2))
        self.effects_ = effects

    def _predict(self, log: InteractionLog) -> np.ndarray:
        return self._current(self.robot_, self.ground_, self.idle_current_a_, self.effects_, log,
                             "track_width_multiplier" in self.fitted_, self.rest_current_a_)

    def _params_to_plain(self) -> dict[str, Any]:
        return {
            "robot": _robot_to_plain(self.robot),
            "ground": _ground_to_plain(self.ground),
            "fit_parameters": list(self.fit_parameters),
            "effects": None if self.effects is None else list(self.effects),
            "clip_negative": self.clip_negative,
        }

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        p = dict(params)
        p["robot"] = _robot_from_plain(p["robot"])
        p["ground"] = _ground_from_plain(p["ground"])
        p["fit_parameters"] = tuple(p["fit_parameters"])
        if p.get("effects") is not None:
            p["effects"] = tuple(p["effects"])
        return p

    def _state(self) -> dict[str, Any]:
        return {
            "robot": dataclasses.asdict(self.robot_),
            "ground": dataclasses.asdict(self.ground_),
            "idle_current_a": self.idle_current_a_,
            "rest_current_a": self.rest_current_a_.tolist(),
            "fitted": dict(self.fitted_),
            "cost": self.cost_,
            "effects": list(self.effects_),
        }

    def _load_state(self, state: dict[str, Any]) -> None:
        self.robot_ = _robot_from_plain({"__robot__": state["robot"]})
        self.ground_ = GroundParams(**state["ground"])
        self.idle_current_a_ = float(state["idle_current_a"])
        if "rest_current_a" in state:
            self.rest_current_a_ = real_array("rest_current_a", state["rest_current_a"]).reshape(2)
        else:  # a file from before the rest level: its idle current was the level at rest and the base of driving
            self.rest_current_a_ = np.full(2, self.idle_current_a_)
            self.idle_current_a_ = 0.0
        self.fitted_ = {str(k): float(v) for k, v in state["fitted"].items()}
        self.cost_ = float(state["cost"])
        self.effects_ = tuple(str(e) for e in state["effects"])
        PhysicsEnergyModel(self.robot_, self.effects_)  # validates the effect names
        if (not all(math.isfinite(v) for v in self.fitted_.values()) or not math.isfinite(self.idle_current_a_)
                or not np.all(np.isfinite(self.rest_current_a_))):
            raise ValueError("non-finite fitted coefficient")
