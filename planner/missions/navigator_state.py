"""A navigator's whole state on disk: written atomically, read back into a navigator that decides as the first would.

Layout of the directory :meth:`planner.Navigator.save` writes (built beside the target under
a temporary name, then renamed into place: a robot killed mid-save keeps its last state):

- ``navigator.json`` — format ``terrawatt-navigator`` (:data:`NAVIGATOR_FORMAT_VERSION`): the
  robot, battery, physics ground, settings, goal and depot; the loop's scalars, records
  (legs, updates, replans, skipped updates, validated pairs), the decision log, a waiting
  manoeuvre request and the regions still to decide;
- ``state.npz`` — the arrays: position, route, series, battery draw, the legs kept for
  driven updates and the chunks since the last checkpoint (every field of each log), the
  vibration signals of learned models, the incremental search's memory;
- ``registry/`` — the per-cell models with their evidence and history
  (:meth:`planner.registry.CellModelRegistry.save`; each model through its own ``save`` and
  :func:`energy.load_current_model`).

Functions here read and write a navigator's attributes; they never import its class, so
:mod:`planner.missions.navigator` may call them.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery, CommandProfile, GroundParams, InteractionLog, LogMeta, RobotParams, load_current_model
from terrain import FileFormatError, InvalidParameterError, TerrainMap
from terrawatt_base.atomic import atomic_directory, check_output_path, json_finite
from terrawatt_base.containers import read_npz
from terrawatt_base.formats import read_result_json, result_document, write_result_json

from ..lattice import Lattice
from ..registry import CellModelRegistry, FlaggedRegion, UpdatePolicy
from ..replan import IncrementalPlanner
from ..route import evaluate_route
from ..settings import PlannerSettings
from .adaptive_results import LegRecord, ReplanRecord, UpdateRecord
from .decisions import ManoeuvreRequest
from .settings import AdaptiveSettings

__all__ = ["NAVIGATOR_FORMAT_VERSION", "write_navigator_state", "read_navigator_setup", "restore_navigator_state"]

NAVIGATOR_FORMAT_VERSION = 2  # 2: the replanner searches over heading (16 states per node)
_KIND = "navigator"
_JSON, _NPZ, _REGISTRY = "navigator.json", "state.npz", "registry"
_LOG_FIELDS = ("time_s", "v_mps", "omega_radps", "current_left_a", "current_right_a", "accel_time_s",
               "accel_z_mps2", "pose_xyh", "ground", "gyro_z_radps", "battery_voltage_v", "battery_current_a")
_SCALARS = ("phase", "status", "reason", "returning", "heading_rad", "leg_start_heading_rad", "leg_start_time_s",
            "time_s", "update_wall", "leg_power_w", "n_chunks", "segment_j", "segment_m", "changed",
            "updates_at_checkpoint", "start_time_ns")


def _num(x: Any) -> float:
    return math.nan if x is None else float(x)


# ------------------------------------------------------------------ write
def _log_arrays(prefix: str, log: InteractionLog, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    for name in _LOG_FIELDS:
        value = getattr(log, name)
        if value is not None:
            arrays[f"{prefix}.{name}"] = np.asarray(value) if name != "ground" else np.asarray(value, dtype=str)
    return asdict(log.meta)


def write_navigator_state(nav: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``nav``'s state to the directory ``path`` atomically (see the module docstring).

    Raises
    ------
    InvalidParameterError
        ``path`` exists and is not a navigator state directory; a model that cannot be saved.
    """
    target = check_output_path(path, "path", directory=True)
    if target.exists() and not (target.is_dir() and ((target / _JSON).is_file() or not any(target.iterdir()))):
        raise InvalidParameterError(f"{str(target)!r} exists and is not a navigator state; refusing to replace it")
    for mid in nav.registry.model_ids:
        if not callable(getattr(nav.registry.model(mid), "save", None)):
            raise InvalidParameterError(f"model {mid} of the registry has no save(path): the state cannot be saved")
    arrays: dict[str, np.ndarray] = {
        "position_xy_m": nav.position_xy_m, "leg_start_xy_m": nav.leg_start_xy_m, "goal_xy_m": nav.goal_xy_m,
        "last_power": np.asarray(nav.charge.last_power, dtype=np.float64),
        "model_map_at_start": np.asarray(nav.model_map_at_start),
    }
    routes = {}
    for name in ("route", "initial_route"):
        r = getattr(nav, name)
        if r is not None:
            arrays[f"{name}.waypoints_m"] = np.asarray(r.waypoints_m)
            routes[name] = {"status": r.status, "planner": r.planner, "planning_time_s": r.planning_time_s}
    if nav.tail is not None:
        arrays["tail"] = np.asarray(nav.tail)
    for key, values in nav.charge.arrays().items():
        arrays[f"series.{key}"] = values
    if nav.charge.draw:
        arrays["draw.t"], arrays["draw.p"] = (np.concatenate(p) for p in zip(*nav.charge.draw))
    metas = {"segment": [_log_arrays(f"segment{i}", log, arrays) for i, log in enumerate(nav.segment)],
             "context": [] if nav.power_context is None else [_log_arrays("context0", nav.power_context, arrays)],
             "history": [_log_arrays(f"history{i}", log, arrays) for i, (log, _, _) in enumerate(nav.history)]}
    for mid, (t, a) in nav.vibrations.items():
        arrays[f"vibration{mid}.t"], arrays[f"vibration{mid}.a"] = t, a
    if nav.replanner is not None:
        for name, arr in nav.replanner.search_state().items():
            arrays[f"search.{name}"] = arr
    queue = []
    for i, region in enumerate(nav.queue):
        arrays[f"queue{i}.rows"], arrays[f"queue{i}.cols"] = region.rows, region.cols
        queue.append({f.name: json_finite(getattr(region, f.name)) for f in fields(region) if f.name not in ("rows", "cols")})
    cfg = asdict(nav.settings)
    doc = result_document(_KIND, NAVIGATOR_FORMAT_VERSION, {
        "robot": nav.robot.to_plain(), "battery": asdict(nav.battery), "physics_ground": asdict(nav.physics_ground),
        "settings": json_finite(cfg), "depot_xy_m": None if nav.depot_xy_m is None else json_finite(list(nav.depot_xy_m)),
        "scalars": {name: json_finite(getattr(nav, name)) for name in _SCALARS},
        "charge": {name: json_finite(getattr(nav.charge, name)) for name in nav.charge.SCALARS},
        "routes": routes, "has_tail": nav.tail is not None, "vibration_ids": sorted(nav.vibrations),
        "pending": json_finite(nav.pending), "observed": json_finite(nav.observed), "pooled": json_finite(list(nav.pooled)),
        "class_samples": [[int(k), int(v)] for k, v in sorted(nav.class_samples.items())],
        "legs": [json_finite(vars(r)) for r in nav.legs], "updates": [json_finite(vars(r)) for r in nav.updates],
        "replans": [json_finite(vars(r)) for r in nav.replans], "skipped": list(nav.skipped),
        "validated": sorted([list(p) for p in nav.validated]), "decisions": nav.decisions,
        "checkpoint_evidence": json_finite(nav.checkpoint_evidence), "queue": queue,
        "request": None if nav.request is None else nav.request.to_dict(), "logs": metas,
        "draw_parts": len(nav.charge.draw), "has_search": nav.replanner is not None,
    })
    with atomic_directory(target) as tmp:
        write_result_json(tmp / _JSON, doc)
        with open(tmp / _NPZ, "wb") as fh:
            np.savez(fh, **arrays)
        nav.registry.save(tmp / _REGISTRY, lambda model, p: model.save(p))
    return target


# ------------------------------------------------------------------ read
def read_navigator_setup(path: str | os.PathLike[str], terrain: TerrainMap) -> dict[str, Any]:
    """What a navigator is built from (registry, robot, battery, physics ground, settings, goal, depot) and the document.

    Raises
    ------
    FileFormatError
        Not a navigator state of this format version; fields of the wrong kind.
    """
    root = Path(path)
    if not (root / _JSON).is_file():
        raise FileFormatError(f"{str(root)!r} is not a navigator state (no {_JSON})")
    doc = read_result_json(root / _JSON, _KIND, NAVIGATOR_FORMAT_VERSION)
    try:
        raw = dict(doc["settings"])
        raw["policy"] = UpdatePolicy(**raw["policy"])
        raw["excitation_speeds_mps"] = tuple(raw["excitation_speeds_mps"])
        settings = AdaptiveSettings(**raw)
        ground = GroundParams(**doc["physics_ground"])
        battery = Battery(**doc["battery"])
        robot = RobotParams.from_plain(doc["robot"], f"{_JSON} robot")
        goal = read_npz(root / _NPZ, "navigator state")["goal_xy_m"]
    except (KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{str(root / _JSON)!r}: a navigator setup field is missing or wrong: {exc}") from None
    depot = doc.get("depot_xy_m")
    registry = CellModelRegistry.load(root / _REGISTRY, load_current_model, terrain=terrain)
    return {"registry": registry, "robot": robot, "battery": battery, "physics_ground": ground, "settings": settings,
            "goal_xy_m": tuple(float(v) for v in goal), "depot_xy_m": None if depot is None else tuple(depot),
            "document": doc}


def _log(prefix: str, meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> InteractionLog:
    values = {name: arrays.get(f"{prefix}.{name}") for name in _LOG_FIELDS}
    return InteractionLog(**values, meta=LogMeta(**meta))


def restore_navigator_state(nav: Any, path: str | os.PathLike[str], document: dict[str, Any]) -> None:
    """Put the saved state into a navigator freshly built from :func:`read_navigator_setup`'s values.

    Raises
    ------
    FileFormatError
        A broken state directory.
    """
    root = Path(path)
    doc = document
    try:
        arrays = read_npz(root / _NPZ, "navigator state")
        for name, value in doc["scalars"].items():
            setattr(nav, name, math.nan if value is None and name in ("time_s",) else value)
        nav.position_xy_m = arrays["position_xy_m"].copy()
        nav.leg_start_xy_m = arrays["leg_start_xy_m"].copy()
        for name, value in doc["charge"].items():
            setattr(nav.charge, name, float(value))
        nav.charge.last_power = tuple(float(v) for v in arrays["last_power"])
        nav.model_map_at_start = arrays["model_map_at_start"].copy()
        for mid in doc["vibration_ids"]:
            t, a = arrays[f"vibration{mid}.t"], arrays[f"vibration{mid}.a"]
            nav.vibrations[int(mid)] = (t, a)
            nav.learned.set_vibration(int(mid), t, a)
        nav.cost = nav.learned.energy_cost(nav.terrain, nav.settings.speed_mps)
        for name, meta in doc["routes"].items():
            wp = arrays[f"{name}.waypoints_m"]
            route = evaluate_route(nav.cost, wp, status=meta["status"], planner=meta["planner"],
                                   planning_time_s=meta["planning_time_s"]) if len(wp) >= 2 else None
            setattr(nav, name, route)
        nav.tail = arrays["tail"].copy() if doc["has_tail"] else None
        nav.charge.series = {k: [arrays[f"series.{k}"]] for k in nav.charge.series}
        nav.charge.draw = [(arrays["draw.t"], arrays["draw.p"])] if doc["draw_parts"] else []
        nav.segment = [_log(f"segment{i}", m, arrays) for i, m in enumerate(doc["logs"]["segment"])]
        for i, m in enumerate(doc["logs"]["history"]):
            log = _log(f"history{i}", m, arrays)
            rows, cols = nav.terrain.rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
            nav.history.append((log, np.asarray(rows), np.asarray(cols)))
        if doc["has_search"]:
            target = nav.depot_xy_m if nav.returning else nav.goal_xy_m
            nav.replanner = IncrementalPlanner(Lattice.for_cost(nav.cost, PlannerSettings().lattice_stride_cells),
                                               tuple(target))
            nav.replanner.restore_search({k.split(".", 1)[1]: v for k, v in arrays.items() if k.startswith("search.")})
        nav.pending = [float(v) for v in doc["pending"]]
        nav.observed = [(float(a), float(b)) for a, b in doc["observed"]]
        nav.pooled = (float(doc["pooled"][0]), float(doc["pooled"][1]))
        nav.class_samples = {int(k): int(v) for k, v in doc["class_samples"]}
        ctx = doc["logs"]["context"]
        nav.power_context = _log("context0", ctx[0], arrays) if ctx else None
        nav.legs = [LegRecord(**{**r, "start_xy_m": tuple(r["start_xy_m"]), "end_xy_m": tuple(r["end_xy_m"])})
                    for r in doc["legs"]]
        nav.updates = [UpdateRecord(**{k: (_num(v) if k.startswith("validation_error") else v)
                                       for k, v in r.items()}) for r in doc["updates"]]
        nav.replans = [ReplanRecord(**{k: (_num(v) if k.endswith("_j") else v) for k, v in r.items()})
                       for r in doc["replans"]]
        nav.skipped = list(doc["skipped"])
        nav.validated = {(int(a), int(b)) for a, b in doc["validated"]}
        nav.decisions = list(doc["decisions"])
        nav.checkpoint_evidence = dict(doc["checkpoint_evidence"])
        nav.queue = [FlaggedRegion(**{**q, "rows": arrays[f"queue{i}.rows"], "cols": arrays[f"queue{i}.cols"],
                                      "bbox_rows_cols": tuple(q["bbox_rows_cols"]),
                                      "representative_row_col": tuple(q["representative_row_col"]),
                                      "representative_xy_m": None if q["representative_xy_m"] is None
                                      else tuple(q["representative_xy_m"]),
                                      "bounds_m": None if q["bounds_m"] is None else tuple(q["bounds_m"]),
                                      "model_ids": tuple(q["model_ids"])})
                     for i, q in enumerate(doc["queue"])]
        req = doc["request"]
        nav.request = None if req is None else ManoeuvreRequest(
            request_id=int(req["request_id"]), ground=req["ground"], region_cells=int(req["region_cells"]),
            xy_m=tuple(req["xy_m"]), duration_s=float(req["duration_s"]),
            estimated_energy_j=_num(req["estimated_energy_j"]), purpose=req["purpose"],
            profiles=tuple(CommandProfile(p["time_s"], p["v_mps"], p["omega_radps"]) for p in req["profiles"]))
        if nav.queue and nav.history:  # the last leg's comparison, while its regions are decided
            log, rows, cols = nav.history[-1]
            nav.resume_comparison(log, rows, cols)
    except (KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{str(root)!r}: a broken navigator state ({type(exc).__name__}: {exc})") from None
