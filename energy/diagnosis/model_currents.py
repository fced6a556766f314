"""The physics basis of a model under diagnosis and its per-side currents before the clamp at 0."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.errors import DataError, InvalidParameterError

from ..drivetrain import DRIVE_EFFECTS
from ..ground import GroundParams
from ..logs import REST_OMEGA_RADPS, REST_SPEED_MPS, InteractionLog, log_slope_rad, rest_samples
from ..models.baselines import PhysicsCurrentModel, ground_slots
from ..params import ground_preset, robot_params
from ..physics import PhysicsEnergyModel
from ..power import PowerBreakdown
from ..robot import RobotParams

__all__ = ["DRIVE_EFFECTS", "TABLE_NODES", "PhysicsBasis", "ParameterTable", "physics_basis", "measured_side_speeds",
           "basis_breakdown", "side_speeds_mps", "standing_samples", "starting_samples", "motoring_currents_a", "unclipped_prediction",
           "clamps_at_zero"]

#: Evenly spaced nodes of a :class:`ParameterTable` over a parameter's bounds (its nominal value is added;
#: computed only where a fit needs them).
TABLE_NODES = 129


@dataclass(frozen=True)
class PhysicsBasis:
    """The physics a model stands on: robot, ground, effects switched on, idle current, rest level.

    For a fitted :class:`~energy.PhysicsCurrentModel` these are its fitted values (``ground``
    one GroundParams or its per-label mapping, ``terrain`` the map whose slope it reads); for
    any other model a reference (the robot's preset on asphalt, every drive effect, level
    ground) from which the physics terms are offered as additive candidates.
    """

    robot: RobotParams
    ground: GroundParams | dict[str, GroundParams]
    effects: tuple[str, ...]
    idle_current_a: float
    fitted_chi: bool
    is_model: bool
    rest_current_a: tuple[float, float] = (0.0, 0.0)
    terrain: Any = None

    def grounds(self) -> list[GroundParams]:
        """Every ground of the basis (one, or one per label)."""
        return list(self.ground.values()) if isinstance(self.ground, dict) else [self.ground]

    def replace_grounds(self, **changes: float) -> GroundParams | dict[str, GroundParams]:
        """The basis's ground (or each of its per-label grounds) with ``changes``."""
        if isinstance(self.ground, dict):
            return {g: p.replace(**changes) for g, p in self.ground.items()}
        return self.ground.replace(**changes)

    def slope_rad(self, log: InteractionLog) -> Any:
        """The slope the basis drives ``log`` on: the pitch under its poses on ``terrain``, else level (0)."""
        return 0.0 if self.terrain is None else log_slope_rad(self.terrain, log)


def physics_basis(model: Any, robot: Any = None) -> PhysicsBasis:
    """The :class:`PhysicsBasis` of ``model`` (``robot``: preset name or RobotParams for other models).

    Raises
    ------
    InvalidParameterError
        ``robot`` is neither None, a preset name nor a RobotParams.
    """
    if isinstance(model, PhysicsCurrentModel) and model.is_fitted:
        return PhysicsBasis(model.robot_, model.fitted_ground, tuple(model.effects_), float(model.idle_current_a_),
                            "track_width_multiplier" in model.fitted_, True,
                            (float(model.rest_current_a_[0]), float(model.rest_current_a_[1])), model.terrain)
    if robot is not None and not isinstance(robot, (str, os.PathLike, RobotParams)):
        raise InvalidParameterError(f"robot must be None, a preset name, a robot file or a RobotParams, got {robot!r:.80}")
    rb = robot_params("husky" if robot is None else robot)
    return PhysicsBasis(rb, ground_preset("asphalt"), DRIVE_EFFECTS, 0.0, False, False,
                        (rb.rest_current_a, rb.rest_current_a))


def measured_side_speeds(log: InteractionLog, robot: RobotParams) -> bool:
    """Whether the log's wheel speeds fix the robot's track multiplier (the rule of
    :class:`~energy.PhysicsCurrentModel`: speeds measured from the wheels, ``omega`` derived
    with ``meta.track_width_m`` at least the robot's track), so that no other value of it
    changes the physics of this log."""
    tw = log.meta.track_width_m
    return log.meta.velocity_source == "measured" and tw is not None and tw / robot.track_width_m >= 1.0


def _log_robot(robot: RobotParams, log: InteractionLog, fitted_chi: bool) -> RobotParams:
    if fitted_chi or not measured_side_speeds(log, robot):
        return robot
    return dataclasses.replace(robot, track_width_multiplier=log.meta.track_width_m / robot.track_width_m)


def basis_breakdown(basis: PhysicsBasis, log: InteractionLog, *, effects: tuple[str, ...] | None = None,
                    robot: RobotParams | None = None, ground: Any = None, ground_index: Any = None,
                    slope_rad: Any = None) -> PowerBreakdown:
    """The :class:`~energy.power.PowerBreakdown` of the physics of ``basis`` (or the given
    ``effects`` / ``robot`` / ``ground``) for the log's ``v``, ``omega``, their time
    derivatives and ``slope_rad`` (default the basis's), with the log's track multiplier rule.

    ``ground`` (or the basis's) may be one GroundParams, a per-label mapping (each sample
    takes its label's) or a list indexed by ``ground_index``.

    Raises
    ------
    DataError
        Fewer than 2 drive samples.
    """
    return _physics(basis, log, effects, robot, ground, ground_index, slope_rad, None)[0]


def _physics(basis: PhysicsBasis, log: InteractionLog, effects: tuple[str, ...] | None, robot: RobotParams | None,
             ground: Any, ground_index: Any, slope_rad: Any,
             still: np.ndarray | None) -> tuple[PowerBreakdown, np.ndarray]:
    """:func:`basis_breakdown`, and the current of holding the robot on the slope at the ``still`` samples
    (N, 2; :meth:`~energy.PhysicsEnergyModel.holding_current_a`; zeros elsewhere, on level ground, and
    everywhere without ``still``)."""
    if len(log) < 2:
        raise DataError(f"the physics terms need at least 2 drive samples per log, got {len(log)} ({log.meta.source!r})")
    rb = _log_robot(basis.robot if robot is None else robot, log, basis.fitted_chi)
    model = PhysicsEnergyModel(rb, basis.effects if effects is None else effects)
    t, v, w = log.time_s, log.v_mps, log.omega_radps
    ground = basis.ground if ground is None else ground
    if ground_index is None:
        ground, ground_index = ground_slots(ground, log)
    slope = basis.slope_rad(log) if slope_rad is None else slope_rad
    res = model.power(v, w, ground, accel_mps2=np.gradient(v, t), alpha_radps2=np.gradient(w, t),
                      slope_rad=slope, time_s=t, ground_index=ground_index)
    held = np.zeros(len(log)) if still is None else np.where(still, slope, 0.0)  # the physics only where it stands
    return res, model.holding_current_a(ground, held, ground_index=ground_index)


def side_speeds_mps(basis: PhysicsBasis, log: InteractionLog) -> np.ndarray:
    """Each side's ground speed (N, 2; left, right), m/s: ``v -/+ omega chi B / 2`` with the basis's track
    multiplier ``chi`` (or the log's, by the rule of :func:`measured_side_speeds`)."""
    rb = _log_robot(basis.robot, log, basis.fitted_chi)
    half = rb.track_width_multiplier * rb.track_width_m / 2.0
    return np.asarray(log.v_mps, float)[:, None] + np.outer(np.asarray(log.omega_radps, float), [-half, half])


def standing_samples(log: InteractionLog) -> np.ndarray:
    """Whether each drive sample stands, as far as the log can tell: the next sample's wheels are
    still (``|v| < REST_SPEED_MPS`` and ``|omega| < REST_OMEGA_RADPS``), and so are this sample's
    or the previous one's. That holds the rests, a stop's last instant (still, yet decelerating)
    and a lone sample of noise-level motion between still ones; a start from rest (the next
    sample moves) is not standing.

    The physics reads a still wheel's intended motion from its acceleration, and a wheel that
    barely moves has its full breakaway, Stribeck and turning-resistance forces (they do not
    shrink with the speed): at a stop's last instant it charges a start in reverse, and at an
    odometry's noise of a few mm/s or 0.01 rad/s a start that never comes — several amperes a
    side the robot never draws.

    Examples
    --------
    >>> import numpy as np
    >>> from energy.logs import InteractionLog
    >>> t = np.arange(8) * 0.2
    >>> v = np.array([0.4, 0.2, 0.0, 0.0, 0.01, 0.0, 0.2, 0.4])  # a stop, a blip, a start
    >>> standing_samples(InteractionLog(t, v, np.zeros(8), None, None, t, np.full(8, 9.81))).tolist()
    [False, False, True, False, True, False, False, False]
    """
    v = np.abs(np.asarray(log.v_mps, dtype=np.float64))
    w = np.abs(np.asarray(log.omega_radps, dtype=np.float64))
    still = (v < REST_SPEED_MPS) & (w < REST_OMEGA_RADPS)
    next_still = np.append(still[1:], still[-1:])
    prev_still = np.concatenate([still[:1], still[:-1]])
    return next_still & (still | prev_still)


def _motoring(basis: PhysicsBasis, log: InteractionLog, still: np.ndarray, *, effects: tuple[str, ...] | None = None,
              robot: RobotParams | None = None, ground: Any = None, ground_index: Any = None,
              slope_rad: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Per-side motor current in the direction of rotation (N, 2), A, everywhere (rests included), and the
    current of holding the robot on the slope at the ``still`` samples (N, 2; zeros elsewhere)."""
    res, holding = _physics(basis, log, effects, robot, ground, ground_index, slope_rad, still)
    i_m = np.asarray(res.motor_current_a)
    sign = np.sign(np.asarray(res.motor_speed_radps))
    return np.where(sign != 0, i_m * sign, np.abs(i_m)), holding


def starting_samples(log: InteractionLog) -> np.ndarray:
    """Whether each drive sample is the still one before a start: its wheels still (``|v| <
    REST_SPEED_MPS``, ``|omega| < REST_OMEGA_RADPS``), the next sample's moving (and not a lone blip of
    noise-level motion, :func:`standing_samples`). At the log's rate
    the start falls anywhere up to the next sample; the physics charges the whole breakaway (and
    the acceleration the next sample shows) at this one."""
    v = np.abs(np.asarray(log.v_mps, dtype=np.float64))
    w = np.abs(np.asarray(log.omega_radps, dtype=np.float64))
    still = (v < REST_SPEED_MPS) & (w < REST_OMEGA_RADPS)
    moves_next = ~np.append(still[1:], True) & ~np.append(standing_samples(log)[1:], False)  # not a lone blip
    return still & moves_next


def motoring_currents_a(basis: PhysicsBasis, log: InteractionLog, *, effects: tuple[str, ...] | None = None,
                        robot: RobotParams | None = None, ground: Any = None, ground_index: Any = None,
                        slope_rad: Any = None, starts: bool = False) -> np.ndarray:
    """Per-side motor current in the direction of rotation (N, 2), A, no idle, no clamp; where the log
    stands, and (unless ``starts``) at the still sample before a start, only the current of holding
    the robot on the slope (0 on level ground).

    The physics of ``basis`` (or the given ``effects`` / ``robot`` / ``ground``, which may be
    a list of GroundParams with ``ground_index``) for the log's ``v``, ``omega``, their time
    derivatives and ``slope_rad`` — what :class:`~energy.PhysicsCurrentModel` predicts: where
    the log stands still (:func:`energy.logs.rest_samples`) no motoring current but the
    holding current, as the model predicts its rest level and that there (a candidate that
    scales gravity, a heavier robot, scales the holding current too). Where
    the log stands otherwise (:func:`standing_samples`: a stop's last instant, noise-level
    motion between still samples) the same, and so at the still sample before a start
    (:func:`starting_samples`) unless ``starts`` (the breakaway itself, judged where it lives):
    the model charges a breakaway there, in reverse at a stop, that the robot may never draw at
    that sample (several amperes a side), and a candidate that scales it (a heavier robot, a
    larger one) would be judged on the model's guess of when the wheels broke away. The
    model's own prediction (:func:`unclipped_prediction`) keeps it.

    Raises
    ------
    DataError
        Fewer than 2 drive samples.
    """
    still = rest_samples(log) | standing_samples(log)
    if not starts:
        still |= starting_samples(log)
    motoring, holding = _motoring(basis, log, still, effects=effects, robot=robot, ground=ground,
                                  ground_index=ground_index, slope_rad=slope_rad)
    return np.where(still[:, None], holding, motoring)


def unclipped_prediction(model: Any, log: InteractionLog, basis: PhysicsBasis | None = None) -> np.ndarray:
    """The model's ``[left, right]`` prediction before its clamp at 0 (N, 2), A.

    A :class:`~energy.PhysicsCurrentModel`: its rest level, plus the idle and the motoring
    current where the log moves; any other model: ``model.predict(log)``.

    Raises
    ------
    DataError
        A physics model that drives a map's slope but holds no map (loaded from a file).
    """
    if basis is not None and basis.is_model:
        model.check_map()
        rest = rest_samples(log)
        motoring, holding = _motoring(basis, log, rest)
        return np.asarray(basis.rest_current_a) + np.where(rest[:, None], holding, basis.idle_current_a + motoring)
    return np.asarray(model.predict(log), dtype=np.float64)


def clamps_at_zero(model: Any) -> bool:
    """Whether the model clamps its currents at 0 (the diagnosis clamps the corrected ones too)."""
    return isinstance(model, PhysicsCurrentModel) and bool(model.clip_negative)


class ParameterTable:
    """The motoring currents of one log re-predicted at nodes of one parameter, linear in between.

    ``repredict(value)`` gives the exact ``(N, 2)`` currents at one parameter value. The
    nodes are :data:`TABLE_NODES` evenly spaced over ``[low, high]`` plus ``nominal`` (so the
    model's own value is exact); each node's currents are computed the first time an
    interpolation needs them and kept, so a least-squares fit reruns the physics only at
    the few nodes around the values it visits, shared by every fold and effect set. It is a
    surrogate for fitting only: scores and predictions use the exact ``repredict``.

    Parameters
    ----------
    repredict : callable
        Exact currents (N, 2) at one value.
    low, high, nominal : float
        Bounds of the parameter and its value in the model under test.
    n_nodes : int
        Evenly spaced nodes (>= 2).
    """

    def __init__(self, repredict: Callable[[float], np.ndarray], low: float, high: float, nominal: float,
                 n_nodes: int = TABLE_NODES, slots: np.ndarray | None = None) -> None:
        nodes = np.linspace(float(low), float(high), int(n_nodes))
        if low <= nominal <= high:
            nodes = np.unique(np.append(nodes, float(nominal)))
        self.repredict = repredict
        self.nodes = nodes
        self.slots = None if slots is None else np.asarray(slots, dtype=np.intp)
        self._rows: dict[int, np.ndarray] = {}
        self._slot_samples: dict[int, np.ndarray] = {}
        self._slot_rows: dict[tuple[int, int], np.ndarray] = {}

    @property
    def n_computed(self) -> int:
        """Nodes whose physics has been computed so far."""
        return len(self._rows)

    def row(self, j: int) -> np.ndarray:
        """Currents (N, 2) at node ``j`` (computed on first use)."""
        j = int(j)
        if j not in self._rows:
            self._rows[j] = np.asarray(self.repredict(float(self.nodes[j])), dtype=np.float64)
        return self._rows[j]

    def at(self, value: Any) -> np.ndarray:
        """Interpolated currents (N, 2) at one value, or at one value per sample (an (N,) array)."""
        nodes = self.nodes
        x = np.clip(np.asarray(value, dtype=np.float64), nodes[0], nodes[-1])
        j = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
        w = (x - nodes[j]) / (nodes[j + 1] - nodes[j])
        if x.ndim == 0:
            return (1.0 - w) * self.row(j) + w * self.row(j + 1)
        out = np.empty((x.size, 2))
        for jj in np.unique(j):
            m = j == jj
            out[m] = (1.0 - w[m])[:, None] * self.row(jj)[m] + w[m][:, None] * self.row(jj + 1)[m]
        return out

    def at_slots(self, values: Any) -> np.ndarray:
        """:meth:`at` with one value per slot: the samples of slot ``k`` (the table's ``slots``) at
        ``values[k]``; equal to ``at(values[slots])``, faster (each slot's rows are gathered once).

        Raises
        ------
        InvalidParameterError
            A table without slots, or fewer values than slots.
        """
        if self.slots is None:
            raise InvalidParameterError("this ParameterTable has no slots; use at()")
        vals = np.asarray(values, dtype=np.float64).reshape(-1)
        if self.slots.size and vals.size <= int(self.slots.max()):
            raise InvalidParameterError(f"at_slots needs a value for each of {int(self.slots.max()) + 1} slots, "
                                        f"got {vals.size}")
        nodes = self.nodes
        out = np.empty((self.slots.size, 2))
        for k in range(vals.size):
            if k not in self._slot_samples:
                self._slot_samples[k] = np.flatnonzero(self.slots == k)
            rows = self._slot_samples[k]
            if rows.size == 0:
                continue
            x = min(max(float(vals[k]), nodes[0]), nodes[-1])
            j = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2))
            w = (x - nodes[j]) / (nodes[j + 1] - nodes[j])
            out[rows] = (1.0 - w) * self._slot_row(k, j) + w * self._slot_row(k, j + 1)
        return out

    def _slot_row(self, k: int, j: int) -> np.ndarray:
        if (k, j) not in self._slot_rows:
            self._slot_rows[(k, j)] = self.row(j)[self._slot_samples[k]]
        return self._slot_rows[(k, j)]
