"""Edge costs from learned current models: per-model energy tables from one batched prediction.

A :class:`LearnedEnergyModel` turns the current models of a
:class:`~planner.registry.CellModelRegistry` into planner edge costs.

For every model it runs **one** ``predict`` call on a synthetic log that holds each speed
of ``speeds_mps`` (straight driving, ``omega = 0``) and then each turn rate of
``omegas_radps`` (turning in place, ``v = 0``) for ``hold_s`` seconds, and averages the
predicted currents over the settled tail of every hold (the first ``settle_s`` seconds of
each hold are left out, so step transients of models that use ``dv/dt`` or windows do not
count). The predicted ``[left, right]`` motor currents become battery power with
:func:`energy.budget.log_battery_power_w` (``current_convention`` as there, electronics off), plus
the robot's electronics (sensor and stable control-board power of
:class:`energy.PhysicsEnergyModel`), and are kept as tables:

- ``energy_per_metre_j[k] = P(speeds_mps[k]) / speeds_mps[k]`` (J/m, flat ground),
- ``turn_energy_per_rad_j[k] = P(omegas_radps[k]) / omegas_radps[k]`` (J/rad).

**Interval.** A model with a predictive interval (``gives_interval``, e.g. the
:class:`energy.VibrationCurrentEstimator`) is asked ``predict_distribution`` instead (one call
too; its mean is ``predict``'s). Its run-level spread ``run_sd_a`` (shared by a whole run on
one ground, both sides fully correlated) becomes the standard deviation of the battery power,
``(P(mean + run_sd) - P(mean - run_sd)) / 2`` through the same
:func:`energy.budget.log_battery_power_w` path, averaged over the settled tail like the mean (fully
correlated: it does not average out), and is tabulated per metre and per radian
(:attr:`LearnedModelTable.energy_per_metre_sd_j`, ``turn_energy_per_rad_sd_j``), with the
forecast's degrees of freedom (:attr:`LearnedModelTable.dof`: ``inf``, a Gaussian, or the
Student-t of a ground the model never drove). The electronics and the physics slope term carry
no spread. :meth:`LearnedEnergyModel.energy_cost` then gives the :class:`EnergyCost`
standard-deviation tables and each row's degrees of freedom (:attr:`CostTables.spread_dof`),
which :func:`planner.price_route` adds up along a route. The per-sample spread averages out over a route and is not
used.

**Vibration input.** Models conditioned on vibration (the
:class:`energy.VibrationCurrentEstimator`) need an acceleration stream. The synthetic log
carries the vertical acceleration observed where the model was trained: register it with
:meth:`LearnedEnergyModel.set_vibration` (e.g. the training log's ``accel_time_s`` /
``accel_z_mps2``); it is tiled over the synthetic log, so the whole-run spectrum the
estimator sees is that of its training ground. Without one, a constant 9.81 m/s^2 (gravity,
no vibration) is used; models that ignore acceleration are unaffected.

**Slope.** Learned models are trained on what the robot drove, mostly flat ground, so they
say nothing reliable about grades. The grade-dependent part comes from the physics model::

    e(v, grade) = e_learned(v) + [e_physics(v, grade) - e_physics(v, 0)]

on ``physics_ground`` (the slope term ``m g sin(beta)`` and the normal-force change of
rolling resistance hardly depend on the ground). Downhill the bracket is negative; the sum
is floored at the electronics' energy per metre (the robot never draws less than its
electronics; with ``regen_efficiency = 0`` the physics model floors the same way). Grades
the drive cannot hold at the planning speed on ``physics_ground`` (climbing, traction or
braking limit) are impassable in the tables (``inf``, in that direction only); predictions
of a driven profile price them at the saturated power instead.

**Caching.** A model's table depends only on the model object (an update adds a *new*
model id; models are never changed in place), so tables are cached per model id and
recomputed only when the registry holds another object under that id (e.g. after
``load``); :attr:`LearnedEnergyModel.table_builds` counts the recomputations. The
per-cell map changes with every registry version; :meth:`LearnedEnergyModel.energy_cost`
rebuilds only the cheap per-cell row index from ``registry.model_id_map``, and with
``previous=`` it derives the new cost with :meth:`EnergyCost.with_tables`, so lattice graphs
are reweighted only where a cell's model changed instead of being rebuilt.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from energy import (
    CommandProfile,
    GroundParams,
    InteractionLog,
    LogMeta,
    PhysicsEnergyModel,
    RobotParams,
    drive_profile,
)
from energy.budget import log_battery_power_w
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2
from terrain import InvalidParameterError, TerrainMap
from terrawatt_base.checks import check_choice, check_instance, check_real, check_text, real_array

from .edge_cost import DEFAULT_MAX_SLOPE_RAD, EnergyCost
from .learned_table import (
    DEFAULT_TABLE_OMEGAS_RADPS,
    DEFAULT_TABLE_SPEEDS_MPS,
    LearnedModelTable,
    TableProbe,
    model_gives_interval,
    predict_current_spread,
    predict_currents,
)
from .registry import CellModelRegistry
from .tables import DEFAULT_GRADE_SAMPLES, DEFAULT_TURN_SAMPLES, CostTables, check_table_sizes, tabulate

__all__ = [
    "LearnedEnergyModel",
    "LearnedModelTable",
    "predict_currents",
    "TableProbe",
    "DEFAULT_TABLE_SPEEDS_MPS",
    "DEFAULT_TABLE_OMEGAS_RADPS",
]

_GRAVITY_MPS2 = 9.81


class LearnedEnergyModel:
    """Energy model over the current models of a registry (the edge-cost protocol).

    Implements ``energy_per_metre_j(speed_mps, grades, ground)`` and
    ``turn_energy_j(angles, ground)`` where ``ground`` is a **model id** of the registry,
    so :meth:`planner.CostSpec.build` can tabulate it with the model ids as pseudo-grounds;
    :meth:`energy_cost` does the same directly from cached tables (the fast path for
    replanning).

    Parameters
    ----------
    registry : CellModelRegistry
        The per-cell models; every model must have ``predict(log) -> (N, 2)`` currents (A).
    robot : RobotParams
        The robot (motor constants for the battery power, electronics, turn rate).
    physics_ground : GroundParams
        Ground of the physics slope term.
    probe : TableProbe, optional
        The table grids and the synthetic log each model is asked on (:class:`TableProbe`,
        default ``TableProbe()``).
    current_convention : {"motor", "battery"}
        What the models' currents are (see :func:`energy.budget.log_battery_power_w`).

    Raises
    ------
    InvalidParameterError
        Bad types, grids or times.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        lem = LearnedEnergyModel(registry, robot_preset("husky"), ground_preset("asphalt"))
        cost = lem.energy_cost(terrain, speed_mps=0.5)
    """

    def __init__(
        self,
        registry: CellModelRegistry,
        robot: RobotParams,
        physics_ground: GroundParams,
        *,
        probe: TableProbe | None = None,
        current_convention: str = "motor",
    ) -> None:
        if not isinstance(registry, CellModelRegistry):
            raise InvalidParameterError(f"registry must be a CellModelRegistry, got {type(registry).__name__!r}")
        if not isinstance(robot, RobotParams):
            raise InvalidParameterError(f"robot must be a RobotParams, got {type(robot).__name__!r}")
        if not isinstance(physics_ground, GroundParams):
            raise InvalidParameterError(f"physics_ground must be a GroundParams, got {type(physics_ground).__name__!r}")
        self.registry = registry
        self.robot = robot
        self.physics_ground = physics_ground
        probe = TableProbe() if probe is None else check_instance("probe", probe, TableProbe)
        #: The table grids and synthetic log (:class:`TableProbe`).
        self.probe = probe
        self.speeds_mps, self.omegas_radps = probe.speeds_mps, probe.omegas_radps
        self.hold_s, self.settle_s, self.rate_hz = probe.hold_s, probe.settle_s, probe.rate_hz
        self.current_convention = check_choice("current_convention", current_convention, ("motor", "battery"))
        self.turn_rate_radps = float(robot.turn_rate_radps)
        self._physics = PhysicsEnergyModel(robot)
        self._electronics = PhysicsEnergyModel(robot, effects=("sensor", "control"))
        self._vibration: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._grounds: dict[int, str] = {}
        self._tables: dict[int, tuple[int, LearnedModelTable]] = {}  # id -> (id(model object), table)
        self._slope_delta: dict[tuple[float, bytes], np.ndarray] = {}  # (speed, grades) -> slope term
        #: Number of per-model tables computed so far (cache misses).
        self.table_builds = 0

    # ------------------------------------------------------------------ vibration
    def set_vibration(self, model_id: int, accel_time_s: Any, accel_z_mps2: Any) -> None:
        """Vertical acceleration to feed model ``model_id`` (e.g. its training log's).

        Invalidates that model's cached table.

        Raises
        ------
        UnknownNameError
            Unknown model id.
        InvalidParameterError
            Arrays of different lengths, fewer than 2 samples, non-finite or non-increasing times.
        """
        self.registry.model(model_id)  # UnknownNameError
        t = real_array("accel_time_s", accel_time_s, ndim=1)
        a = real_array("accel_z_mps2", accel_z_mps2, ndim=1)
        if a.shape != t.shape or t.size < 2 or not np.all(np.diff(t) > 0):
            raise InvalidParameterError(f"accel_time_s (strictly increasing) and accel_z_mps2 must have the same "
                                        f"length >= 2, got {t.shape!r} and {a.shape!r}")
        self._vibration[int(model_id)] = (t - t[0], a)
        self._tables.pop(int(model_id), None)

    def set_ground(self, model_id: int, ground: str) -> None:
        """The ground model ``model_id`` prices its cells as (a training ground's name, e.g. ``"snow"``).

        Its forecasts are asked for that ground: a ground the model drove gives that ground's
        own run spread (Gaussian), any other the new-ground spread (a Student-t, see
        :mod:`energy.models.forecast`); without one every cell is a ground the model never
        drove. Invalidates that model's cached table.

        Raises
        ------
        UnknownNameError
            Unknown model id.
        InvalidParameterError
            ``ground`` is not a non-empty string.
        """
        self.registry.model(model_id)  # UnknownNameError
        self._grounds[int(model_id)] = check_text("ground", ground)
        self._tables.pop(int(model_id), None)

    # ------------------------------------------------------------------ tables
    def _accel_signal(self, model_id: int, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Vertical acceleration for model ``model_id`` over ``[0, duration_s + 1]`` s: its stored
        vibration repeated end to end, or gravity alone (100 Hz) when none was set."""
        if model_id in self._vibration:
            ta, az = self._vibration[model_id]
            period = ta[-1] + (ta[-1] - ta[0]) / (ta.size - 1)
            reps = int(math.ceil((duration_s + 1.0) / period)) + 1
            return (ta[None, :] + period * np.arange(reps)[:, None]).reshape(-1), np.tile(az, reps)
        at = np.arange(0.0, duration_s + 1.0 + 1e-9, 0.01)
        return at, np.full(at.size, _GRAVITY_MPS2)

    def _synthetic_log(self, model_id: int) -> tuple[InteractionLog, np.ndarray]:
        n_hold = max(2, int(round(self.hold_s * self.rate_hz)))
        levels_v = np.concatenate([self.speeds_mps, np.zeros(self.omegas_radps.size)])
        levels_w = np.concatenate([np.zeros(self.speeds_mps.size), self.omegas_radps])
        n = n_hold * levels_v.size
        t = np.arange(n) / self.rate_hz
        v = np.repeat(levels_v, n_hold)
        w = np.repeat(levels_w, n_hold)
        at, accel = self._accel_signal(model_id, float(t[-1]))
        zeros = np.zeros(n)
        log = InteractionLog(t, v, w, zeros, zeros, at, accel,
                             meta=LogMeta(robot=self.robot.name, source=f"learned-cost table of model {model_id}",
                                          ground_label=self._grounds.get(model_id)))
        # settled tail of each hold
        settle = int(round(self.settle_s * self.rate_hz))
        keep = (np.arange(n) % n_hold) >= settle
        return log, keep

    def table(self, model_id: int) -> LearnedModelTable:
        """The flat-ground tables of model ``model_id`` (cached; built with one ``predict`` call).

        Raises
        ------
        UnknownNameError
            Unknown model id.
        InvalidParameterError
            The model's prediction is not ``(N, 2)`` finite currents, or the resulting energies are negative.
        """
        model = self.registry.model(model_id)
        mid = int(model_id)
        cached = self._tables.get(mid)
        if cached is not None and cached[0] == id(model):
            return cached[1]
        t0 = time.perf_counter()
        log, keep = self._synthetic_log(mid)
        run_sd, dof = None, math.inf
        if model_gives_interval(model):
            pred, run_sd, dof = predict_current_spread(model, log, self._label(mid))
        else:
            pred = predict_currents(model, log, self._label(mid))
        drive_w = self._drive_power_w(log, pred)
        n_levels = self.speeds_mps.size + self.omegas_radps.size
        level = np.arange(len(log)) * n_levels // len(log)
        sel = level[keep]
        counts = np.bincount(sel, minlength=n_levels)
        mean_drive_w = np.bincount(sel, weights=drive_w[keep], minlength=n_levels) / counts
        sd_w = None
        if run_sd is not None:  # both sides and every sample fully correlated: the spreads add linearly
            half_w = 0.5 * np.abs(self._drive_power_w(log, pred + run_sd) - self._drive_power_w(log, pred - run_sd))
            sd_w = np.bincount(sel, weights=half_w[keep], minlength=n_levels) / counts
        mean_current = np.column_stack([np.bincount(sel, weights=pred[keep, k], minlength=n_levels) / counts
                                        for k in range(2)])
        levels_v = np.concatenate([self.speeds_mps, np.zeros(self.omegas_radps.size)])
        levels_w = np.concatenate([np.zeros(self.speeds_mps.size), self.omegas_radps])
        elec_w = self._electronics.power(levels_v, levels_w, self.physics_ground).total_power_w
        power_w = mean_drive_w + elec_w
        ns = self.speeds_mps.size
        e_per_m = power_w[:ns] / self.speeds_mps
        e_per_rad = power_w[ns:] / self.omegas_radps
        if np.any(e_per_m < 0) or np.any(e_per_rad < 0):
            raise InvalidParameterError(
                f"model {mid} predicts negative battery power (J/m {e_per_m.tolist()!r}, J/rad "
                f"{e_per_rad.tolist()!r}); edge costs must be >= 0"
            )
        sd_per_m = None if sd_w is None else sd_w[:ns] / self.speeds_mps
        sd_per_rad = None if sd_w is None else sd_w[ns:] / self.omegas_radps
        table = LearnedModelTable(mid, self.speeds_mps, e_per_m, self.omegas_radps, e_per_rad, mean_current,
                                  time.perf_counter() - t0, sd_per_m, sd_per_rad, dof)
        self._tables[mid] = (id(model), table)
        self.table_builds += 1
        return table

    def _drive_power_w(self, log: InteractionLog, currents_a: np.ndarray) -> np.ndarray:
        """Battery power (W) of the drive sides of ``log`` drawing ``currents_a`` (N, 2), electronics off."""
        plog = InteractionLog(log.time_s, log.v_mps, log.omega_radps, currents_a[:, 0], currents_a[:, 1],
                              log.accel_time_s, log.accel_z_mps2, meta=log.meta)
        return log_battery_power_w(plog, self.robot, current_convention=self.current_convention, electronics=False)

    @property
    def gives_interval(self) -> bool:
        """Whether some model in use has a predictive interval (its table carries spreads > 0)."""
        return any(self.table(int(m)).has_interval for m in self.registry.model_ids_in_use().tolist())

    def profile_energy_j(self, terrain: TerrainMap, profile: CommandProfile, *, speed_mps: float | None = None) -> float:
        """Predicted battery energy (J) of driving a command profile across the map.

        Every sample's current comes from the model serving the cell under its pose (fed that
        model's vibration, :meth:`set_vibration`), turned into battery power with the same
        bookkeeping as a driven log (:func:`energy.budget.log_battery_power_w`, electronics
        included) and integrated over time; the physics slope term (module docstring) is
        added per metre along the path. Unlike the edge costs, which price steady driving at
        one speed plus turns in place, this prices the whole velocity profile: starting and
        stopping at every waypoint, slow pivots, time spent accelerating.

        Parameters
        ----------
        terrain : TerrainMap
            The registry's map.
        profile : CommandProfile
            Commands with poses (e.g. :func:`energy.drive_profile`).
        speed_mps : float, optional
            Speed of the slope term's physics evaluation; default the profile's top speed.

        Returns
        -------
        float

        Raises
        ------
        GridMismatchError
            ``terrain`` is not the registry's grid.
        InvalidParameterError
            A profile without poses or with fewer than 2 samples.
        OutOfBoundsError
            A pose outside the map.
        """
        self.registry.check_grid(terrain)
        if not isinstance(profile, CommandProfile) or profile.pose_xyh is None:
            raise InvalidParameterError("profile must be a CommandProfile with poses (pose_xyh)")
        t = np.asarray(profile.time_s, dtype=np.float64)
        if t.size < 2:
            raise InvalidParameterError(f"profile must have at least 2 samples, got {t.size}")
        v = np.asarray(profile.v_mps, dtype=np.float64)
        w = np.asarray(profile.omega_radps, dtype=np.float64)
        pose = np.asarray(profile.pose_xyh, dtype=np.float64)
        rows, cols = terrain.rowcol(pose[:, 0], pose[:, 1])
        ids = np.asarray(self.registry.model_id_map)[rows, cols]
        power = np.empty(t.size)
        zeros = np.zeros(t.size)
        t_rel = t - t[0]
        for mid in np.unique(ids).tolist():
            at, accel = self._accel_signal(int(mid), float(t_rel[-1]))
            log = InteractionLog(t_rel, v, w, zeros, zeros, at, accel,
                                 meta=LogMeta(robot=self.robot.name, source=f"profile prediction, model {mid}"))
            pred = predict_currents(self.registry.model(int(mid)), log, self._label(int(mid)))
            plog = InteractionLog(t_rel, v, w, pred[:, 0], pred[:, 1], at, accel, meta=log.meta)
            sel = ids == mid
            power[sel] = log_battery_power_w(plog, self.robot, current_convention=self.current_convention)[sel]
        energy = float(np.trapezoid(power, t))
        speed = float(np.max(np.abs(v))) if speed_mps is None else float(speed_mps)
        if speed > 0:
            heading = pose[:, 2]
            grade = terrain["grad_x"][rows, cols] * np.cos(heading) + terrain["grad_y"][rows, cols] * np.sin(heading)
            grade = np.where(v < 0, -grade, grade)
            metres = np.abs(v) * np.gradient(t)
            energy += float(np.sum(self._grade_delta_j(speed, grade, infeasible="capped") * metres))
        return energy

    def predict_route_energy_j(
        self,
        terrain: TerrainMap,
        waypoints_m: Any,
        speed_mps: float,
        *,
        start_heading_rad: float | None = None,
        dt_s: float = 0.05,
        accel_mps2: float = DEFAULT_ACCEL_MPS2,
        yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2,
    ) -> float:
        """Predicted battery energy (J) of driving a route the way :func:`planner.simulate_mission` does.

        :meth:`profile_energy_j` of :func:`energy.drive_profile` (stop, pivot at the robot's
        turn rate, drive each segment rest to rest at ``speed_mps``).

        Raises
        ------
        InvalidParameterError, OutOfBoundsError, GridMismatchError
            As :func:`energy.drive_profile` and :meth:`profile_energy_j`.
        """
        profile = drive_profile(waypoints_m, speed_mps, turn_rate_radps=self.turn_rate_radps, dt_s=dt_s,
                                accel_mps2=accel_mps2, yaw_accel_radps2=yaw_accel_radps2,
                                start_heading_rad=start_heading_rad)
        return self.profile_energy_j(terrain, profile, speed_mps=speed_mps)

    def refresh(self) -> list[int]:
        """Build the tables of every model in use that has none yet (or changed); return their ids."""
        built = []
        for mid in self.registry.model_ids_in_use().tolist():
            before = self.table_builds
            self.table(mid)
            if self.table_builds != before:
                built.append(int(mid))
        return built

    # ------------------------------------------------------------------ protocol
    def _electronics_per_metre_j(self, speed: float) -> float:
        return float(self._electronics.energy_per_metre_j(speed, 0.0, self.physics_ground))

    def _label(self, model_id: int) -> str:
        return f"model {model_id} ({self.registry.model_record(model_id).name!r})"

    def _slope_term_j(self, speed: float, grades: np.ndarray) -> np.ndarray:
        """:meth:`_grade_delta_j` of planning tables, cached per (speed, grade grid): tables of
        every model share one grade grid, so the physics runs once per grid."""
        key = (speed, grades.shape, grades.tobytes())
        delta = self._slope_delta.get(key)
        if delta is None:
            delta = self._grade_delta_j(speed, grades)
            delta.setflags(write=False)
            self._slope_delta[key] = delta
        return delta

    def _grade_delta_j(self, speed: float, grades: np.ndarray, infeasible: str = "inf") -> np.ndarray:
        """Physics slope term (J/m): ``inf`` on grades the drive cannot hold at ``speed`` for
        planning tables; ``infeasible="capped"`` prices them at the saturated power (what
        driving there anyway draws), for predictions of routes being driven."""
        phys = self._physics.energy_per_metre_j
        return (np.asarray(phys(speed, grades, self.physics_ground, infeasible=infeasible), dtype=np.float64)
                - float(phys(speed, 0.0, self.physics_ground, infeasible="capped")))

    def energy_per_metre_j(self, speed_mps: float, grade: Any, model_id: int, /) -> np.ndarray:
        """J per metre travelled at ``speed_mps`` on ``grade`` for the model with id ``model_id``
        (this model's cell class: :class:`energy.EnergyModel`).

        ``e_learned(v) + [e_physics(v, grade) - e_physics(v, 0)]``, floored at the
        electronics' J/m (see the module docstring).

        Raises
        ------
        UnknownNameError
            Unknown model id.
        InvalidParameterError
            Non-positive speed, NaN grades.
        """
        speed = check_real("speed_mps", speed_mps, low=0.0, low_inclusive=False)
        try:
            grades = np.asarray(grade, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"grade must be numbers, got {grade!r:.80}") from exc
        if np.any(np.isnan(grades)):
            raise InvalidParameterError("grade must not hold NaN")
        flat = self.table(int(model_id)).energy_per_metre_at(speed)
        return np.maximum(flat + self._slope_term_j(speed, grades), self._electronics_per_metre_j(speed))

    def turn_energy_j(self, heading_change_rad: Any, model_id: int, /) -> np.ndarray:
        """J of turning in place by ``|heading_change_rad|`` at the robot's turn rate, model ``model_id``.

        Raises
        ------
        UnknownNameError
            Unknown model id.
        """
        angles = np.abs(np.asarray(heading_change_rad, dtype=np.float64))
        return angles * self.table(int(model_id)).turn_energy_per_rad_at(self.turn_rate_radps)

    def energy_per_metre_sd_j(self, speed_mps: float, grade: Any, model_id: int, /) -> np.ndarray:
        """Run-level standard deviation (J per metre travelled) of :meth:`energy_per_metre_j`.

        The learned flat-ground spread at ``speed_mps``, the same on every grade (the physics
        slope term has none); 0 for a model without an interval.

        Raises
        ------
        UnknownNameError
            Unknown model id.
        """
        speed = check_real("speed_mps", speed_mps, low=0.0, low_inclusive=False)
        grades = np.asarray(grade, dtype=np.float64)
        return np.full(grades.shape, self.table(int(model_id)).energy_per_metre_sd_at(speed))

    def turn_energy_sd_j(self, heading_change_rad: Any, model_id: int, /) -> np.ndarray:
        """Run-level standard deviation (J) of :meth:`turn_energy_j`; 0 for a model without an interval."""
        angles = np.abs(np.asarray(heading_change_rad, dtype=np.float64))
        return angles * self.table(int(model_id)).turn_energy_per_rad_sd_at(self.turn_rate_radps)

    # ------------------------------------------------------------------ edge costs
    def energy_cost(
        self,
        terrain: TerrainMap,
        speed_mps: float,
        *,
        max_slope_rad: float = DEFAULT_MAX_SLOPE_RAD,
        grade_samples: int = DEFAULT_GRADE_SAMPLES,
        turn_samples: int = DEFAULT_TURN_SAMPLES,
        previous: EnergyCost | None = None,
    ) -> EnergyCost:
        """An :class:`EnergyCost` whose table rows are the models in use (cell row = its model).

        Equal to :meth:`planner.CostSpec.build` with this adapter as the energy model on a map whose ground classes are the model ids,
        but only the tables of models not yet cached are computed. When a model in use has
        a predictive interval, the cost also carries the standard-deviation tables
        (:func:`planner.tables.tabulate` with ``spread=True``; zero rows for models without one).

        With ``previous`` (a cost this adapter made earlier for the same map, speed, slope
        limit and table sizes), the result is ``previous.with_tables(...)``: the map geometry
        is shared and lattice graphs cached on ``previous`` are carried over, recomputing
        only the edges that cross cells whose model (table content) changed — the fast path
        of a replan after a model update. The result is equal to a fresh build.

        Raises
        ------
        GridMismatchError
            ``terrain`` is not on the registry's grid.
        InvalidParameterError
            Bad speed or table sizes.
        """
        t0 = time.perf_counter()
        self.registry.check_grid(terrain)
        speed = check_real("speed_mps", speed_mps, low=0.0, low_inclusive=False)
        slope = check_real("max_slope_rad", max_slope_rad, low=0.0, high=math.pi / 2, low_inclusive=False,
                           high_inclusive=False)
        n_grade, n_turn = check_table_sizes(grade_samples, turn_samples)
        if previous is not None:
            if not isinstance(previous, EnergyCost):
                raise InvalidParameterError(f"previous must be an EnergyCost or None, got {type(previous).__name__!r}")
            if not ((previous.terrain is terrain or previous.terrain.same_grid(terrain))
                    and (previous.speed_mps, previous.max_slope_rad) == (speed, slope)
                    and (previous.tables.grade_table_j_per_m.shape[1], previous.tables.turn_table_j.shape[1]) == (n_grade, n_turn)):
                raise InvalidParameterError(
                    f"previous ({previous!r}) was built for another grid, speed, slope limit or table size; "
                    f"expected speed_mps={speed!r}, max_slope_rad={slope!r}, "
                    f"grade_samples={grade_samples!r}, turn_samples={turn_samples!r}"
                )
        ids = self.registry.model_ids_in_use()
        labels = tuple(self.registry.model_record(int(m)).name for m in ids.tolist())
        grade_table, turn_table = tabulate(
            self, speed, ids.tolist(), labels, max_slope_rad=slope, grade_samples=n_grade, turn_samples=n_turn
        )
        grade_sd = turn_sd = spread_dof = None
        if any(self.table(int(m)).energy_per_metre_sd_j is not None for m in ids.tolist()):
            grade_sd, turn_sd = tabulate(self, speed, ids.tolist(), labels, max_slope_rad=slope,
                                         grade_samples=n_grade, turn_samples=n_turn, spread=True)
            spread_dof = tuple(self.table(int(m)).dof for m in ids.tolist())
        lut = np.zeros(int(ids.max()) + 1, dtype=np.int32)
        lut[ids] = np.arange(ids.size, dtype=np.int32)
        rows = lut[np.asarray(self.registry.model_id_map)]
        tables = CostTables(grade_table, turn_table, labels, grade_sd, turn_sd, spread_dof)
        if previous is not None:
            cost = previous.with_tables(tables, rows)
        else:
            cost = EnergyCost(terrain, rows, tables, speed_mps=speed, max_slope_rad=slope,
                              battery_voltage_v=self.robot.battery_voltage_v, turn_rate_radps=self.turn_rate_radps)
        cost.learned_model = self  # a route's whole drive profile is priced by this model (price_route)
        cost.prep_time_s = time.perf_counter() - t0
        return cost

    def __repr__(self) -> str:
        return (f"LearnedEnergyModel(robot={self.robot.name!r}, models={len(self.registry.model_ids)}, "
                f"cached={sorted(self._tables)}, table_builds={self.table_builds})")
