"""The adaptive mission loop: plan, drive a leg, compare per cell, update models, replan.

:func:`run_adaptive_mission` plans with the registry's current models (through
:class:`~planner.learned_cost.LearnedEnergyModel` edge costs), drives the route leg by leg
against a :class:`energy.TruthSimulator` (which knows the true grounds), records measured vs
predicted current per cell in the :class:`terrain.CellModelRegistry`, and where the
:class:`terrain.UpdatePolicy` flags a region it

1. runs the excitation manoeuvre there (:func:`energy.excitation_commands`: a straight run
   over speed levels and a pivot run, simulated on the spot on the ground of the region's
   representative cell; its energy and time are charged to the battery),
2. fits a new model (``model_factory``, default :class:`energy.LinearCurrentModel`) on the
   first ``1 - validation_fraction`` of each excitation log,
3. validates new and old model on the held-back tails (absolute relative error of the
   integrated absolute current, both sides) and calls ``registry.propose_update``, which
   keeps the new model only if it is better,
4. refreshes the edge costs (only the new model's table is computed, and the lattice graph
   is reweighted only where cells changed model: ``energy_cost(..., previous=cost)``) and
   replans from the current position.

Before exciting a flagged region, the loop tries the models it already has: the one that
best explains what the last leg measured in the region (integrated current, both sides) is
assigned to the update's scope without a manoeuvre when its error is under the policy
threshold and below the serving model's on the same samples (``UpdateRecord.kind ==
"reuse"``; a registry version like any other, so it rolls back). Without a segmentation
(``"region"``) this is what keeps a ground learned once from being excited again at every
new patch of it.

A (ground class, model) pair is excited at most once: the model fitted there, or the old
model that beat it, has been validated on fresh excitation data of that ground, so later
flags of the same pair only reset the evidence (the cells' error then comes from the
transients — pivots, stops — that small regions over-represent).

The scope of an update is, with ``update_scope="ground_class"`` (default), every cell of the
map's ground class at the representative cell that is served by the same model(s) as the
flagged region: the map's ground layer is used as a *segmentation* only (e.g. surface classes
from imagery), never for its energy; with ``"region"`` only the flagged cells.

Predictions (of each leg, of the remaining route for the budget check and after a replan)
price the velocity profile the robot will drive with the models serving the cells it crosses
(:meth:`LearnedEnergyModel.profile_energy_j` of the stop-turn-go profile): the edge costs the
planner minimises price steady driving plus turns in place, and miss the energy of stopping
and starting at every waypoint and leg end (a few per cent per 10 m leg, more with turns).
Both are recorded (``LegRecord.route_energy_j`` is the edge-cost figure). A remaining route
is predicted as the loop drives it: leg by leg, stopping at every leg end.

The loop stops at the goal, when the predicted energy of the remaining route exceeds the
energy above the battery's reserve (``"budget_exceeded"``), when the reserve is crossed while
driving (``"reserve_violated"``), when no route is found (``"no_route"``) or after
``max_legs`` legs (``"max_legs"``); the result says why and where.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import (
    Battery,
    GroundParams,
    InteractionLog,
    LinearCurrentModel,
    RobotParams,
    TruthSimulator,
    excitation_commands,
    log_battery_power_w,
)
from terrain import CellModelRegistry, InvalidParameterError, TerrainMap, UpdatePolicy
from terrain.atomic import atomic_path, write_json_atomic

from .learned_cost import LearnedEnergyModel, predict_currents
from .mission import simulate_mission
from .ompl_planner import plan_route
from .route import Route, evaluate_route

__all__ = [
    "ADAPTIVE_STATUSES",
    "ADAPTIVE_FORMAT_VERSION",
    "UPDATE_SCOPES",
    "AdaptiveSettings",
    "LegRecord",
    "UpdateRecord",
    "ReplanRecord",
    "AdaptiveResult",
    "run_adaptive_mission",
    "validation_error",
]

ADAPTIVE_STATUSES = ("completed", "budget_exceeded", "reserve_violated", "no_route", "max_legs")
ADAPTIVE_FORMAT_VERSION = 1
UPDATE_SCOPES = ("ground_class", "region")


@dataclass(frozen=True, kw_only=True)
class AdaptiveSettings:
    """Knobs of :func:`run_adaptive_mission`.

    Parameters
    ----------
    speed_mps : float
        Planning and driving speed (m/s, > 0).
    leg_length_m : float
        Length of route driven between comparisons (m, > 0).
    policy : UpdatePolicy
        When a cell's error calls for an update.
    update_scope : {"ground_class", "region"}
        Cells an update covers (see the module docstring).
    planner : str
        Planner name for :func:`plan_route` (default ``"lattice"``).
    planner_time_limit_s : float
        OMPL time budget (s; ignored by the lattice).
    excitation_duration_s, turn_excitation_duration_s : float
        Lengths of the straight and pivot excitation runs (s, > 2).
    excitation_speeds_mps : tuple of float
        Speed levels of the straight excitation run.
    excitation_omega_radps : float
        Pivot rate of the turn excitation run (rad/s, > 0).
    validation_fraction : float
        Held-back tail of each excitation log, in (0, 0.5].
    max_updates : int
        Update attempts allowed (>= 0).
    max_legs : int
        Legs allowed (>= 1).
    goal_tolerance_m : float
        Distance to the goal that counts as arrived (m, > 0).
    seed : int
        Seeds the drives and excitations (>= 0).
    """

    speed_mps: float = 0.5
    leg_length_m: float = 10.0
    policy: UpdatePolicy = field(default_factory=lambda: UpdatePolicy(threshold_pct=10.0, min_samples=50,
                                                                      hysteresis_pct=3.0, min_region_cells=8))
    update_scope: str = "ground_class"
    planner: str = "lattice"
    planner_time_limit_s: float = 1.0
    excitation_duration_s: float = 20.0
    turn_excitation_duration_s: float = 8.0
    excitation_speeds_mps: tuple[float, ...] = (0.2, 0.35, 0.5, 0.65, 0.8)
    excitation_omega_radps: float = 0.5
    validation_fraction: float = 0.25
    max_updates: int = 5
    max_legs: int = 500
    goal_tolerance_m: float = 0.5
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("speed_mps", "leg_length_m", "planner_time_limit_s", "excitation_omega_radps", "goal_tolerance_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InvalidParameterError(f"AdaptiveSettings.{name} must be a finite number > 0, got {v!r}")
        for name in ("excitation_duration_s", "turn_excitation_duration_s"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 2.0):
                raise InvalidParameterError(f"AdaptiveSettings.{name} must be a finite number > 2 s, got {v!r}")
        if not isinstance(self.policy, UpdatePolicy):
            raise InvalidParameterError(f"AdaptiveSettings.policy must be an UpdatePolicy, got {self.policy!r}")
        if self.update_scope not in UPDATE_SCOPES:
            raise InvalidParameterError(f"AdaptiveSettings.update_scope must be one of {UPDATE_SCOPES!r}, got {self.update_scope!r}")
        if not (isinstance(self.validation_fraction, (int, float)) and 0 < self.validation_fraction <= 0.5):
            raise InvalidParameterError(f"AdaptiveSettings.validation_fraction must be in (0, 0.5], got {self.validation_fraction!r}")
        speeds = tuple(float(s) for s in self.excitation_speeds_mps)
        if not speeds or any(not (math.isfinite(s) and s > 0) for s in speeds):
            raise InvalidParameterError(f"AdaptiveSettings.excitation_speeds_mps must be numbers > 0, got {self.excitation_speeds_mps!r}")
        object.__setattr__(self, "excitation_speeds_mps", speeds)
        for name, low in (("max_updates", 0), ("max_legs", 1), ("seed", 0)):
            v = getattr(self, name)
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= low):
                raise InvalidParameterError(f"AdaptiveSettings.{name} must be an integer >= {low}, got {v!r}")


@dataclass(frozen=True)
class LegRecord:
    """One driven leg: where, predicted and actual battery energy (J), duration (s).

    ``predicted_energy_j`` prices the leg's velocity profile with the models in use before it
    was driven; ``route_energy_j`` is the planner's edge-cost energy of the same leg.
    """

    index: int
    start_xy_m: tuple[float, float]
    end_xy_m: tuple[float, float]
    predicted_energy_j: float
    actual_energy_j: float
    duration_s: float
    n_samples: int
    route_energy_j: float


@dataclass(frozen=True)
class UpdateRecord:
    """One model update attempt after leg ``after_leg``."""

    after_leg: int
    ground: str
    region_cells: int
    scope_cells: int
    region_error_pct: float
    accepted: bool
    model_id: int | None
    validation_error_new: float
    validation_error_old: float
    excitation_energy_j: float
    excitation_duration_s: float
    wall_time_s: float
    kind: str = "excitation"  # or "reuse": a model learned elsewhere assigned without a manoeuvre


@dataclass(frozen=True)
class ReplanRecord:
    """A (re)plan: when, the remaining route's predicted energy, whether the route changed."""

    after_leg: int
    reason: str
    predicted_energy_j: float
    previous_route_energy_j: float
    route_changed: bool
    refresh_time_s: float
    planning_time_s: float
    tables_built: int


@dataclass(frozen=True, eq=False)
class AdaptiveResult:
    """Outcome of :func:`run_adaptive_mission` (see the module docstring).

    Attributes
    ----------
    status, reason : str
        One of :data:`ADAPTIVE_STATUSES` and a sentence saying why the loop stopped.
    final_xy_m : (float, float)
        Where the robot is at the end.
    distance_to_goal_m : float
    initial_route : Route
        The first plan (prior models).
    legs, updates, replans : tuple of records
    time_s, x_m, y_m, soc, energy_j, predicted_energy_j : ndarray
        Series over the whole mission (driving and excitation), cumulative energies (J).
    driven_energy_j, excitation_energy_j : float
        Actual battery energy of driving and of the excitation manoeuvres (J).
    update_wall_time_s : float
        Wall-clock time spent fitting/validating/refreshing for updates (s).
    final_soc : float
    skipped_updates : tuple of str
        Updates not attempted because the excitation manoeuvre and the remaining route did not
        both fit above the reserve, one sentence each.
    """

    status: str
    reason: str
    final_xy_m: tuple[float, float]
    distance_to_goal_m: float
    initial_route: Route
    legs: tuple[LegRecord, ...]
    updates: tuple[UpdateRecord, ...]
    replans: tuple[ReplanRecord, ...]
    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    soc: np.ndarray
    energy_j: np.ndarray
    predicted_energy_j: np.ndarray
    driven_energy_j: float
    excitation_energy_j: float
    update_wall_time_s: float
    final_soc: float
    skipped_updates: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.status not in ADAPTIVE_STATUSES:
            raise InvalidParameterError(f"status must be one of {ADAPTIVE_STATUSES!r}, got {self.status!r}")

    # ------------------------------------------------------------------ metrics
    @property
    def accepted_updates(self) -> int:
        """Number of accepted updates."""
        return sum(u.accepted for u in self.updates)

    def _legs_error_pct(self, legs: list[LegRecord]) -> float:
        pred = sum(leg.predicted_energy_j for leg in legs)
        act = sum(leg.actual_energy_j for leg in legs)
        return 100.0 * (pred - act) / act if act > 0 else math.nan

    @property
    def error_before_update_pct(self) -> float:
        """Prediction error (%) of the legs driven before the first accepted update (all legs if none)."""
        first = next((u.after_leg for u in self.updates if u.accepted), None)
        return self._legs_error_pct([lg for lg in self.legs if first is None or lg.index <= first])

    @property
    def error_after_update_pct(self) -> float:
        """Prediction error (%) of the legs driven after the last accepted update (NaN if none)."""
        last = next((u.after_leg for u in reversed(self.updates) if u.accepted), None)
        if last is None:
            return math.nan
        return self._legs_error_pct([lg for lg in self.legs if lg.index > last])

    @property
    def remaining_error_after_update_pct(self) -> float:
        """Error (%) of the remaining-route prediction made right after the last accepted update
        against the energy actually driven from there (NaN without update or unfinished)."""
        last = next((u.after_leg for u in reversed(self.updates) if u.accepted), None)
        plan = next((p for p in reversed(self.replans) if p.after_leg == last), None) if last is not None else None
        if plan is None or self.status != "completed":
            return math.nan
        act = sum(lg.actual_energy_j for lg in self.legs if lg.index > last)
        return 100.0 * (plan.predicted_energy_j - act) / act if act > 0 else math.nan

    @property
    def route_changes(self) -> int:
        """Replans that changed the route."""
        return sum(p.route_changed for p in self.replans if p.reason != "initial")

    def to_json_dict(self, *, series_every: int = 10) -> dict[str, Any]:
        """Plain JSON data (non-finite numbers become ``None``); series every ``series_every`` samples."""
        def num(x: Any) -> Any:
            if isinstance(x, (float, np.floating)):
                return float(x) if math.isfinite(x) else None
            if isinstance(x, (np.integer,)):
                return int(x)
            if isinstance(x, tuple):
                return [num(v) for v in x]
            return x

        def rec(r: Any) -> dict[str, Any]:
            return {k: num(v) for k, v in vars(r).items()}

        k = max(1, int(series_every))
        return {
            "format": "terrawatt-adaptive-mission",
            "format_version": ADAPTIVE_FORMAT_VERSION,
            "status": self.status,
            "reason": self.reason,
            "final_xy_m": num(self.final_xy_m),
            "distance_to_goal_m": num(self.distance_to_goal_m),
            "final_soc": num(self.final_soc),
            "initial_route": self.initial_route.summary(),
            "initial_route_waypoints_m": self.initial_route.waypoints_m.tolist(),
            "driven_energy_j": num(self.driven_energy_j),
            "excitation_energy_j": num(self.excitation_energy_j),
            "update_wall_time_s": num(self.update_wall_time_s),
            "accepted_updates": self.accepted_updates,
            "route_changes": self.route_changes,
            "error_before_update_pct": num(self.error_before_update_pct),
            "error_after_update_pct": num(self.error_after_update_pct),
            "remaining_error_after_update_pct": num(self.remaining_error_after_update_pct),
            "legs": [rec(r) for r in self.legs],
            "updates": [rec(r) for r in self.updates],
            "skipped_updates": list(self.skipped_updates),
            "replans": [rec(r) for r in self.replans],
            "series": {name: [num(v) for v in getattr(self, name)[::k].tolist()]
                       for name in ("time_s", "x_m", "y_m", "soc", "energy_j", "predicted_energy_j")},
        }

    def save_json(self, path: str | os.PathLike[str], *, series_every: int = 10) -> Path:
        """Write :meth:`to_json_dict` atomically to ``path``; return the path."""
        return write_json_atomic(path, self.to_json_dict(series_every=series_every), indent=1, default=str)

    def plot(self, path: str | os.PathLike[str], terrain: TerrainMap, registry: CellModelRegistry) -> Path:
        """Four panels: route over cells coloured by model and by error, SoC, cumulative energy."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(2, 2, figsize=(11, 9))
        x0, y0 = terrain.origin_xy_m
        rows, cols = terrain.shape
        ext = (x0, x0 + cols * terrain.cell_size_m, y0, y0 + rows * terrain.cell_size_m)
        from matplotlib.colors import BoundaryNorm, ListedColormap
        from matplotlib.patches import Patch

        id_map = np.asarray(registry.model_id_map)
        ids = np.unique(id_map)
        palette = plt.get_cmap("tab10").colors
        colours = [palette[i % len(palette)] for i in range(ids.size)]
        # one discrete colour per model in use, named in the legend
        ax[0, 0].imshow(np.searchsorted(ids, id_map), origin="lower", extent=ext, interpolation="nearest",
                        cmap=ListedColormap(colours), norm=BoundaryNorm(np.arange(ids.size + 1) - 0.5, ids.size))
        model_patches = [Patch(color=c, label=f"{int(m)}: {registry.model_record(int(m)).name}")
                         for m, c in zip(ids.tolist(), colours)]
        ax[0, 0].set_title("cells by model")
        with np.errstate(invalid="ignore"):
            err = 100.0 * np.abs(registry.relative_error())
        im = ax[0, 1].imshow(err, origin="lower", extent=ext, cmap="magma", interpolation="nearest")
        fig.colorbar(im, ax=ax[0, 1], label="|error| of current (%) since last reset")
        ax[0, 1].set_title("cells by observed error")
        for a in (ax[0, 0], ax[0, 1]):
            wp = self.initial_route.waypoints_m
            if wp.size:
                a.plot(wp[:, 0], wp[:, 1], "w--", lw=1, label="initial plan")
            a.plot(self.x_m, self.y_m, "c-", lw=1.5, label="driven")
            a.set_xlabel("x (m)")
            a.set_ylabel("y (m)")
        handles, _ = ax[0, 0].get_legend_handles_labels()
        ax[0, 0].legend(handles=handles + model_patches, loc="upper left", fontsize=7, framealpha=0.85)
        ax[0, 1].legend(loc="upper left", fontsize=7)
        ax[1, 0].plot(self.time_s, 100.0 * self.soc)
        ax[1, 0].set_xlabel("time (s)")
        ax[1, 0].set_ylabel("state of charge (%)")
        ax[1, 1].plot(self.time_s, self.energy_j / 3600.0, label="actual (driving + excitation manoeuvres)")
        ax[1, 1].plot(self.time_s, self.predicted_energy_j / 3600.0, label="predicted (driving; flat while exciting)")
        ax[1, 1].set_xlabel("time (s)")
        ax[1, 1].set_ylabel("cumulative energy (Wh)")
        ax[1, 1].legend()
        fig.suptitle(f"adaptive mission: {self.status}")
        fig.tight_layout()
        target = Path(path)
        try:
            with atomic_path(target) as tmp:
                fig.savefig(tmp, dpi=90, format="png")
        finally:
            plt.close(fig)
        return target


# ----------------------------------------------------------------------- helpers
def validation_error(model: Any, logs: list[InteractionLog]) -> float:
    """Absolute relative error of the integrated absolute current (both sides) over ``logs``.

    ``|sum |I_pred| dt - sum |I_meas| dt| / sum |I_meas| dt`` (lower is better); the metric
    :func:`run_adaptive_mission` compares old and new models with.
    """
    pred = meas = 0.0
    for log in logs:
        dt = np.gradient(log.time_s)
        p = np.abs(predict_currents(model, log, f"model {model!r:.60}")).sum(axis=1)
        m = np.abs(log.current_left_a) + np.abs(log.current_right_a)
        pred += float(np.sum(p * dt))
        meas += float(np.sum(m * dt))
    if meas <= 0:
        raise InvalidParameterError("validation logs hold no current; cannot validate")
    return abs(pred - meas) / meas


def fit_prior_model(truth: TruthSimulator, ground: str, seed: int = 1) -> LinearCurrentModel:
    """A prior current model: a :class:`energy.LinearCurrentModel` fitted on one ground.

    It drives two excitation manoeuvres on ``ground`` in the truth simulator — straight runs
    at 0.2–0.8 m/s (30 s) and pivot turns at ±0.5 rad/s (12 s) — and fits the linear model
    to both, which is what a robot commissioned on that one ground would know.

    Parameters
    ----------
    truth : TruthSimulator
        Simulator that knows ``ground``.
    ground : str
        Ground name the prior is trained on (a key of ``truth``'s grounds).
    seed : int
        Seed of the manoeuvres and the simulated noise.

    Returns
    -------
    LinearCurrentModel
        The fitted prior.

    Raises
    ------
    UnknownNameError
        If ``truth`` does not know ``ground``.
    """
    straight = excitation_commands(
        30.0, speed_levels_mps=(0.2, 0.35, 0.5, 0.65, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=seed
    )
    pivot = excitation_commands(
        12.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
        hold_s=(2.0, 3.0), rest_s=0.0, seed=seed + 1,
    )
    logs = [
        truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=ground, seed=seed + 10 + i)
        for i, p in enumerate((straight, pivot))
    ]
    return LinearCurrentModel().fit(logs)


def _split_polyline(wp: np.ndarray, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The first ``length_m`` of a polyline and the rest (sharing the cut point)."""
    seg = np.hypot(*np.diff(wp, axis=0).T)
    cum = np.concatenate(([0.0], np.cumsum(seg)))
    if cum[-1] <= length_m + 1e-9:
        return wp, wp[-1:]
    k = int(np.searchsorted(cum, length_m, side="right"))  # cut inside segment k-1
    f = (length_m - cum[k - 1]) / seg[k - 1]
    cut = wp[k - 1] + f * (wp[k] - wp[k - 1])
    head = np.vstack([wp[:k], cut])
    tail = np.vstack([cut, wp[k:]])
    if np.hypot(*(head[-1] - head[-2])) < 1e-9:
        head = head[:-1]
    if np.hypot(*(tail[1] - tail[0])) < 1e-9:
        tail = tail[1:]
    return head, tail


def _predicted_currents(registry: CellModelRegistry, log: InteractionLog, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Each sample's current from the model serving its cell (one predict per model in use)."""
    ids = np.asarray(registry.model_id_map)[rows, cols]
    out = np.empty((len(log), 2))
    for mid in np.unique(ids).tolist():
        sel = ids == mid
        out[sel] = predict_currents(registry.model(mid), log, f"model {mid} ({registry.model_record(mid).name!r})")[sel]
    return out


def _best_other_model(
    registry: CellModelRegistry, log: InteractionLog, in_region: np.ndarray, measured_a: np.ndarray,
    dt_s: np.ndarray, serving: tuple[int, ...], min_samples: int,
) -> tuple[int, float] | None:
    """The registry model that best explains the log's samples in a region, unless it alone
    already serves the whole region (``serving``: the ids serving its cells): ``(model id,
    |predicted - measured| / measured)`` of the integrated absolute current (both sides), or
    None with fewer than ``min_samples`` samples or no candidate."""
    if np.count_nonzero(in_region) < min_samples or not np.any(measured_a[in_region]):
        return None
    best: tuple[int, float] | None = None
    for mid in registry.model_ids:
        if tuple(serving) == (mid,):  # assigning it would change nothing
            continue
        pred = predict_currents(registry.model(mid), log, f"model {mid} ({registry.model_record(mid).name!r})")
        err = _charge_error(pred, measured_a, dt_s, in_region)
        if best is None or err < best[1]:
            best = (int(mid), err)
    return best


def _charge_error(predicted_a: np.ndarray, measured_a: np.ndarray, dt_s: np.ndarray, sel: np.ndarray) -> float:
    """``|Q_pred - Q_meas| / Q_meas`` of the absolute current (both sides) over the samples ``sel``."""
    q_meas = float(np.sum(np.abs(measured_a[sel]).sum(axis=1) * dt_s[sel]))
    q_pred = float(np.sum(np.abs(predicted_a[sel]).sum(axis=1) * dt_s[sel]))
    return abs(q_pred - q_meas) / q_meas


def _log_energy_j(log: InteractionLog, robot: RobotParams) -> float:
    return float(np.trapezoid(log_battery_power_w(log, robot), log.time_s))


def _time_to_spend_j(logs: list[InteractionLog], robot: RobotParams, energy_j: float) -> float:
    """Seconds into the logs, played one after another, when their battery energy reaches ``energy_j``."""
    from scipy.integrate import cumulative_trapezoid

    elapsed = 0.0
    for log in logs:
        t = log.time_s - log.time_s[0]
        cum = cumulative_trapezoid(log_battery_power_w(log, robot), t, initial=0.0)  # non-decreasing: power >= 0
        if cum[-1] >= energy_j:
            return elapsed + float(np.interp(energy_j, cum, t))
        energy_j -= float(cum[-1])
        elapsed += float(t[-1])
    return elapsed


# ----------------------------------------------------------------------- the loop
def run_adaptive_mission(
    terrain: TerrainMap,
    registry: CellModelRegistry,
    robot: RobotParams,
    battery: Battery,
    truth: TruthSimulator,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    physics_ground: GroundParams,
    settings: AdaptiveSettings | None = None,
    model_factory: Callable[[], Any] | None = None,
    learned: LearnedEnergyModel | None = None,
) -> AdaptiveResult:
    """Drive from start to goal, updating per-cell current models and replanning.

    Parameters
    ----------
    terrain : TerrainMap
        The map (the truth simulator looks up its true grounds by the map's ground names).
    registry : CellModelRegistry
        Per-cell models on the map's grid (changed in place by accepted updates).
    robot : RobotParams
        The robot (normally ``truth.robot``).
    battery : Battery
        Capacity, voltage, reserve and initial state of charge.
    truth : TruthSimulator
        Drives the legs and the excitation manoeuvres.
    start_xy_m, goal_xy_m : (float, float)
        World coordinates (m).
    physics_ground : GroundParams
        Ground of the physics slope term of the learned edge costs.
    settings : AdaptiveSettings, optional
    model_factory : callable, optional
        Returns a new unfitted current model (``fit(logs)`` / ``predict(log)``); default
        :class:`energy.LinearCurrentModel`.
    learned : LearnedEnergyModel, optional
        Edge-cost adapter over ``registry`` (to reuse its table cache); built when None.

    Returns
    -------
    AdaptiveResult

    Raises
    ------
    InvalidParameterError
        Wrong argument types; ``learned`` bound to another registry.
    GridMismatchError
        ``registry`` on another grid.
    OutOfBoundsError, BlockedPositionError
        Start or goal outside the map or blocked.
    """
    for name, value, cls in (("terrain", terrain, TerrainMap), ("registry", registry, CellModelRegistry),
                             ("robot", robot, RobotParams), ("battery", battery, Battery),
                             ("truth", truth, TruthSimulator), ("physics_ground", physics_ground, GroundParams)):
        if not isinstance(value, cls):
            raise InvalidParameterError(f"{name} must be a {cls.__name__}, got {type(value).__name__!r}")
    registry.check_grid(terrain)
    cfg = AdaptiveSettings() if settings is None else settings
    if not isinstance(cfg, AdaptiveSettings):
        raise InvalidParameterError(f"settings must be an AdaptiveSettings, got {type(cfg).__name__!r}")
    factory = LinearCurrentModel if model_factory is None else model_factory
    lem = learned if learned is not None else LearnedEnergyModel(registry, robot, physics_ground)
    if lem.registry is not registry:
        raise InvalidParameterError("learned must be a LearnedEnergyModel over the same registry")
    goal = np.asarray(goal_xy_m, dtype=np.float64)
    capacity_j = battery.energy_capacity_j

    def plan(pos: np.ndarray, cost: Any) -> Route:
        return plan_route(terrain, tuple(pos), tuple(goal), cost=cost, planner=cfg.planner,
                          time_limit_s=cfg.planner_time_limit_s, seed=cfg.seed, compare=False)

    dt_s = 1.0 / truth.current_rate_hz

    def predict_leg(waypoints: np.ndarray, heading: float | None) -> float:
        """Energy of driving ``waypoints`` (one leg, rest to rest) from ``heading`` with the models in use now."""
        if len(waypoints) < 2 or not np.any(np.hypot(*np.diff(waypoints, axis=0).T) > 0):
            return 0.0
        return lem.predict_route_energy_j(terrain, waypoints, cfg.speed_mps, start_heading_rad=heading, dt_s=dt_s)

    def predict_legs(waypoints: np.ndarray, heading: float | None) -> list[float]:
        """Energy of each leg of a route driven the way the loop does: leg by leg, stopping at
        each leg's end (kept until the route or the models change, then recomputed)."""
        energies, rest = [], np.asarray(waypoints, dtype=np.float64)
        while len(rest) >= 2:
            leg, rest = _split_polyline(rest, cfg.leg_length_m)
            energies.append(predict_leg(leg, heading))
            d = np.diff(leg, axis=0)
            d = d[np.hypot(d[:, 0], d[:, 1]) > 0]
            if len(d):
                heading = float(np.arctan2(d[-1, 1], d[-1, 0]))
        return energies

    t0 = time.perf_counter()
    builds0 = lem.table_builds
    cost = lem.energy_cost(terrain, cfg.speed_mps)
    refresh = time.perf_counter() - t0
    route = plan(np.asarray(start_xy_m, dtype=np.float64), cost)
    initial_route = route
    pending = predict_legs(route.waypoints_m, None) if route.found else []  # remaining legs' energies (J)
    replans = [ReplanRecord(0, "initial", sum(pending) if route.found else math.nan, math.nan,
                            True, refresh, route.planning_time_s, lem.table_builds - builds0)]
    legs: list[LegRecord] = []
    updates: list[UpdateRecord] = []
    series: dict[str, list[np.ndarray]] = {k: [] for k in ("t", "x", "y", "soc", "e", "p")}
    pos = np.asarray(start_xy_m, dtype=np.float64)
    heading: float | None = None
    soc = battery.initial_soc
    clock = e_total = p_total = 0.0
    driven_j = excitation_j = update_wall = 0.0
    validated: set[tuple[int, int]] = set()  # (ground class, model id) pairs validated on excitation data
    skipped: list[str] = []  # updates not attempted for lack of energy

    def push(t: np.ndarray, x: np.ndarray, y: np.ndarray, s: np.ndarray, e: np.ndarray, p: np.ndarray) -> None:
        for key, arr in zip(("t", "x", "y", "soc", "e", "p"), (t, x, y, s, e, p)):
            series[key].append(np.asarray(arr, dtype=np.float64))

    push(np.array([0.0]), pos[:1], pos[1:], np.array([soc]), np.array([0.0]), np.array([0.0]))
    status, reason = "max_legs", f"stopped after max_legs={cfg.max_legs} legs"
    for leg_index in range(cfg.max_legs):
        if np.hypot(*(pos - goal)) <= cfg.goal_tolerance_m:
            status, reason = "completed", "reached the goal"
            break
        if not route.found:
            status, reason = "no_route", f"no route from {tuple(pos.round(2))} to the goal (planner status {route.status!r})"
            break
        avail_j = (soc - battery.reserve_soc) * capacity_j
        need_j = sum(pending)
        if need_j > avail_j:
            status = "budget_exceeded"
            reason = (f"the remaining route needs {need_j / 3600:.2f} Wh (predicted) but only "
                      f"{max(avail_j, 0.0) / 3600:.2f} Wh are left above the {battery.min_reserve_pct:g} % reserve")
            break
        head, tail = _split_polyline(np.asarray(route.waypoints_m), cfg.leg_length_m)
        leg_route = evaluate_route(cost, head, status="exact", planner="leg")
        leg_pred_j = pending.pop(0) if pending else predict_leg(head, heading)
        mr = simulate_mission(terrain, leg_route, robot, battery.replace(initial_soc=soc), truth, cost,
                              speed_mps=cfg.speed_mps, start_heading_rad=heading, stop_at_reserve=True,
                              seed=cfg.seed + 1000 + leg_index)
        budget = mr.budget
        legs.append(LegRecord(leg_index, (float(pos[0]), float(pos[1])), (float(mr.x_m[-1]), float(mr.y_m[-1])),
                              leg_pred_j, float(budget.actual_energy_j), float(mr.duration_s),
                              int(mr.n_samples), float(budget.predicted_energy_j)))
        e_leg = np.asarray(mr.energy_wh) * 3600.0
        # the edge-cost prediction's progress along the leg, scaled to the profile prediction
        p_leg = np.asarray(mr.predicted_energy_wh) * 3600.0
        if budget.predicted_energy_j > 0:
            p_leg = p_leg * (leg_pred_j / budget.predicted_energy_j)
        push(clock + mr.time_s, mr.x_m, mr.y_m, mr.soc, e_total + e_leg, p_total + p_leg)
        clock += float(mr.time_s[-1])
        e_total += float(budget.actual_energy_j)
        p_total += leg_pred_j
        driven_j += float(budget.actual_energy_j)
        soc = float(mr.soc[-1])
        pos = np.array([mr.x_m[-1], mr.y_m[-1]])
        heading = float(mr.heading_rad[-1])
        if mr.status == "reserve_violated":
            status = "reserve_violated"
            xy = mr.reserve_crossed_xy_m
            reason = f"the battery reached its {battery.min_reserve_pct:g} % reserve at {xy!r} m during leg {leg_index}"
            break
        # compare measured and predicted current per cell
        log = mr.log
        rows, cols = terrain.rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
        pred = _predicted_currents(registry, log, np.asarray(rows), np.asarray(cols))
        meas = np.column_stack([log.current_left_a, log.current_right_a])
        dt = np.gradient(log.time_s)
        registry.record(rows, cols, np.abs(meas), np.abs(pred), dt)
        changed = False
        for region in registry.flagged_regions(cfg.policy):
            if sum(u.kind == "excitation" for u in updates) >= cfg.max_updates:
                break
            w0 = time.perf_counter()
            r, c = region.representative_row_col
            gid = int(terrain.ground[r, c])
            gname = terrain.ground_names.get(gid, str(gid))
            old_id = int(np.asarray(registry.model_id_map)[r, c])
            if cfg.update_scope == "ground_class":
                scope = (np.asarray(terrain.ground) == gid) & np.isin(np.asarray(registry.model_id_map),
                                                                      np.asarray(region.model_ids))
            else:
                scope = region.mask(registry.shape)
            # A model learned elsewhere may already explain what this leg measured in the
            # region: assign it without a manoeuvre (the registry keeps it as a new version).
            in_region = region.mask(registry.shape)[rows, cols]
            reuse = _best_other_model(registry, log, in_region, meas, dt, region.model_ids, cfg.policy.min_samples)
            if reuse is not None:
                mid, err = reuse
                err_now = _charge_error(pred, meas, dt, in_region)  # the serving model(s), same samples
                if err < min(cfg.policy.threshold_pct / 100.0, err_now):
                    registry.assign(scope, mid, reason=(
                        f"reuse: model {mid} ({registry.model_record(mid).name!r}) explains the {gname!r} region "
                        f"driven in leg {leg_index} to {100 * err:.1f} % (the serving model: {100 * err_now:.1f} %)"))
                    changed = True
                    wall = time.perf_counter() - w0
                    update_wall += wall
                    updates.append(UpdateRecord(leg_index, gname, region.cell_count, int(np.count_nonzero(scope)),
                                                100.0 * region.relative_error, True, mid, err, err_now,
                                                0.0, 0.0, wall, kind="reuse"))
                    continue
            if (gid, old_id) in validated:
                # this model already proved itself on fresh excitation data of this ground: the
                # cells' error comes from transients (pivots, stops) they over-represent
                registry.reset_evidence(region)
                continue
            # Afford the manoeuvre? Estimated at the last leg's mean battery power, it and the
            # remaining route as predicted now must both fit above the reserve; else skip it.
            x_t_est = cfg.excitation_duration_s + cfg.turn_excitation_duration_s
            x_e_est = float(budget.actual_energy_j) / max(float(mr.duration_s), 1e-9) * x_t_est
            if x_e_est > (soc - battery.reserve_soc) * capacity_j - sum(pending):
                skipped.append(f"after leg {leg_index}: no {gname!r} update, its ~{x_e_est / 3600:.2f} Wh "
                               "manoeuvre and the remaining route do not both fit above the reserve")
                registry.reset_evidence(region)
                continue
            seed = cfg.seed + 10_000 + 10 * len(updates)
            straight = excitation_commands(cfg.excitation_duration_s, 1.0 / truth.current_rate_hz,
                                           speed_levels_mps=cfg.excitation_speeds_mps, omega_levels_radps=(0.0,),
                                           rest_s=0.0, seed=seed)
            turn = excitation_commands(cfg.turn_excitation_duration_s, 1.0 / truth.current_rate_hz,
                                       speed_levels_mps=(0.0,), omega_levels_radps=(cfg.excitation_omega_radps,),
                                       omega_sign="both", hold_s=(2.0, 3.0), rest_s=0.0, seed=seed + 1)
            xlogs = [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=gname, seed=seed + 2 + i)
                     for i, p in enumerate((straight, turn))]
            x_e = sum(_log_energy_j(xl, robot) for xl in xlogs)
            x_t = sum(float(xl.time_s[-1] - xl.time_s[0]) for xl in xlogs)
            avail_j = (soc - battery.reserve_soc) * capacity_j
            if x_e > avail_j:  # it costs more than estimated: it stops at the reserve, nothing is learned
                x_t = _time_to_spend_j(xlogs, robot, avail_j)
                excitation_j += avail_j
                e_total += avail_j
                clock += x_t
                soc = battery.reserve_soc
                push(np.array([clock]), pos[:1], pos[1:], np.array([soc]), np.array([e_total]), np.array([p_total]))
                update_wall += time.perf_counter() - w0
                status = "reserve_violated"
                reason = (f"the battery reached its {battery.min_reserve_pct:g} % reserve {x_t:.1f} s into the "
                          f"{gname!r} excitation manoeuvre at {tuple(pos.round(2).tolist())!r} m after leg "
                          f"{leg_index}; no update was made from the incomplete data")
                break
            train, held = [], []
            for xl in xlogs:
                cut = xl.time_s[0] + (1.0 - cfg.validation_fraction) * (xl.time_s[-1] - xl.time_s[0])
                train.append(xl.slice(xl.time_s[0], cut))
                held.append(xl.slice(cut, xl.time_s[-1] + 1.0))
            new_model = factory().fit(train)
            err_new = validation_error(new_model, held)
            err_old = validation_error(registry.model(old_id), held)
            decision = registry.propose_update(
                scope, new_model, err_new, err_old, name=f"update{len(updates) + 1}-{gname}",
                reason=f"region error {100 * region.relative_error:+.1f} % after leg {leg_index}",
                meta={"ground": gname, "after_leg": leg_index})
            if decision.accepted:
                lem.set_vibration(decision.model_id, xlogs[0].accel_time_s, xlogs[0].accel_z_mps2)
                validated.add((gid, int(decision.model_id)))
                changed = True
            else:
                validated.add((gid, old_id))
                registry.reset_evidence(region)
            excitation_j += x_e
            soc -= x_e / capacity_j
            clock += x_t
            e_total += x_e
            push(np.array([clock]), pos[:1], pos[1:], np.array([soc]), np.array([e_total]), np.array([p_total]))
            wall = time.perf_counter() - w0
            update_wall += wall
            updates.append(UpdateRecord(leg_index, gname, region.cell_count, int(np.count_nonzero(scope)),
                                        100.0 * region.relative_error, bool(decision.accepted), decision.model_id,
                                        err_new, err_old, x_e, x_t, wall))
        if status == "reserve_violated":
            break
        if changed:
            t1 = time.perf_counter()
            builds0 = lem.table_builds
            cost = lem.energy_cost(terrain, cfg.speed_mps, previous=cost)  # lattice reweighted, not rebuilt
            refresh = time.perf_counter() - t1
            old_energy = evaluate_route(cost, tail).energy_j if len(tail) >= 2 else 0.0
            route = plan(pos, cost)
            if route.found:
                same = route.waypoints_m.shape == tail.shape and np.allclose(route.waypoints_m, tail, atol=1e-6)
                if not same and old_energy <= route.energy_j:  # planner found nothing better: keep the old one
                    route, same = evaluate_route(cost, tail, status="exact", planner="kept"), True
                pending = predict_legs(route.waypoints_m, heading)  # the models changed
            else:
                same, pending = False, []
            update_wall += refresh
            replans.append(ReplanRecord(leg_index, "update", sum(pending) if route.found else math.nan, old_energy,
                                        not same, refresh, route.planning_time_s, lem.table_builds - builds0))
        elif len(tail) >= 2:
            route = evaluate_route(cost, tail, status="exact", planner=route.planner)
        else:
            status, reason = "completed", "reached the goal"
            break
    cat = {k: np.concatenate(v) for k, v in series.items()}
    return AdaptiveResult(
        status=status, reason=reason, final_xy_m=(float(pos[0]), float(pos[1])),
        distance_to_goal_m=float(np.hypot(*(pos - goal))), initial_route=initial_route, legs=tuple(legs),
        updates=tuple(updates), replans=tuple(replans), time_s=cat["t"], x_m=cat["x"], y_m=cat["y"],
        soc=cat["soc"], energy_j=cat["e"], predicted_energy_j=cat["p"], driven_energy_j=driven_j,
        excitation_energy_j=excitation_j, update_wall_time_s=update_wall, final_soc=soc,
        skipped_updates=tuple(skipped),
    )
