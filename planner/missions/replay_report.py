"""A recorded drive replayed from names and files: what ``terrawatt replay`` does, as one library call."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from energy import GROUND_PRESETS, Battery, InteractionLog, ground_preset, load_current_model
from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..cost_spec import CostSpec
from ..model_cost import model_energy_model
from ..registry import CellModelRegistry
from .navigator import Navigator
from .replay import ReplayResult, replay_drive
from .settings import AdaptiveSettings, MissionGoal, NavigatorModels, ReplayFeed

__all__ = ["replay_recording", "place_by_gps"]

def place_by_gps(logs: Sequence[InteractionLog], track: Any, terrain: TerrainMap,
                 max_gap_s: float = 2.0) -> list[InteractionLog]:
    """The logs with their positions from GPS fixes (a :class:`energy.io.NavSatTrack` on the logs'
    clock) projected through the map's CRS and interpolated onto the drive timestamps; the heading
    stays the log's (odometry) where it has one, else the track's direction of travel.

    Raises
    ------
    InvalidParameterError
        The map has no CRS.
    DataError
        Fewer than two fixes; a drive sample farther than ``max_gap_s`` from any fix.
    """
    if terrain.crs is None:
        raise InvalidParameterError("GPS fixes are placed on a map through its CRS, and this map has none")
    ok = np.isfinite(track.lon_deg) & np.isfinite(track.lat_deg) & (np.asarray(track.status) >= 0)
    t = np.asarray(track.time_s)[ok]
    if t.size < 2:
        raise DataError(f"the GPS topic {track.topic!r} of {track.source!r} holds fewer than two fixes")
    x, y = (np.asarray(v, dtype=np.float64) for v in terrain.lonlat_to_xy(track.lon_deg[ok], track.lat_deg[ok]))
    out = []
    for log in logs:
        ts = log.time_s
        near = np.abs(ts[:, None] - t[np.clip(np.searchsorted(t, ts)[:, None] + np.array([-1, 0]), 0, t.size - 1)])
        far = near.min(axis=1) > max_gap_s
        if far.any():
            i = int(np.argmax(far))
            raise DataError(f"{log.meta.source!r}: no GPS fix within {max_gap_s:g} s of the drive sample at "
                            f"t = {float(ts[i]):.3f} s")
        xi, yi = np.interp(ts, t, x), np.interp(ts, t, y)
        if log.pose_xyh is not None:
            heading = log.pose_xyh[:, 2]
        else:
            heading = np.arctan2(np.gradient(yi), np.gradient(xi))
        out.append(replace(log, pose_xyh=np.column_stack([xi, yi, heading])))
    return out


def replay_recording(
    terrain: TerrainMap,
    logs: Sequence[InteractionLog],
    goal: MissionGoal | None = None,
    *,
    battery: Battery | None = None,
    pricing: CostSpec | None = None,
    settings: AdaptiveSettings | None = None,
    registry: str | os.PathLike[str] | CellModelRegistry | None = None,
    physics_ground: str = "asphalt",
    feed: ReplayFeed | None = None,
    map_label: str = "map",
) -> ReplayResult:
    """Replay a recorded drive through a navigator set up as ``terrawatt mission`` sets up its loop.

    The models at the start: a saved registry (``registry``: a directory, e.g. the
    ``start_registry/`` that an adaptive mission writes with its ``logs``, or a :class:`planner.registry.CellModelRegistry`),
    or one saved current model (``model``) serving every cell — per ground class through
    :func:`planner.model_cost.model_energy_model` when ``model_ground`` says how. With a
    ``feed.state_path`` that holds a saved navigator, the replay resumes from it and these (and
    the goal) are not needed.

    Parameters
    ----------
    terrain : TerrainMap
    logs : sequence of InteractionLog
        The recording (:func:`energy.io.read_logs`).
    goal : MissionGoal
        The goal, in map metres or WGS 84 degrees, and the depot to return to
        (:class:`~planner.missions.settings.MissionGoal`); not needed when resuming.
    battery : Battery
        The battery, with its state of charge at the start of the recording (e.g.
        :func:`~planner.missions.mission_report.mission_battery`, ``.replace(initial_soc=...)``);
        not needed when resuming.
    pricing : CostSpec, optional
        The robot, its driving speed, the saved current ``model`` the drive starts with (and its
        ``model_ground``) and the navigator's ``risk`` (:class:`planner.cost_spec.CostSpec`;
        default ``CostSpec()``); the edges are priced by the per-cell models, so its slope limit
        and unknown ground do not apply.
    settings : AdaptiveSettings, optional
        The navigator's settings (legs, seed, update source, interval level, ...; default
        ``AdaptiveSettings()``); its speed and risk are the spec's.
    registry
        The models at the start (above): a saved registry, instead of ``pricing.model``.
    physics_ground : str
        Ground preset of the physics slope term of the edge costs.
    feed : ReplayFeed, optional
        Legs or chunks, the pace, the state's folder and who hears the decisions, as
        :func:`~planner.missions.replay.replay_drive` (default ``ReplayFeed()``).
    map_label : str
        The map's name in the result's summary.

    Returns
    -------
    ReplayResult

    Raises
    ------
    InvalidParameterError
        Neither or both of ``registry`` and ``model`` (unless resuming); no goal or battery (unless
        resuming); bad numbers.
    UnknownNameError
        ``physics_ground`` without a preset.
    """
    feed = ReplayFeed() if feed is None else check_instance("feed", feed, ReplayFeed)
    resuming = feed.resumes
    if physics_ground not in GROUND_PRESETS:
        raise UnknownNameError(f"physics_ground {physics_ground!r} has no preset; known grounds: "
                               f"{sorted(GROUND_PRESETS)!r}", parameter="physics_ground")
    ground = ground_preset(physics_ground)
    pricing = CostSpec.given(pricing)
    robot_given, model = pricing.params, pricing.model
    settings = AdaptiveSettings() if settings is None else check_instance("settings", settings, AdaptiveSettings)
    settings = replace(settings, speed_mps=pricing.speed_mps, risk=pricing.risk)
    if resuming:
        return replace(replay_drive(Navigator.load(feed.state_path, terrain), logs, feed=feed), map_label=map_label)
    learned = None
    if (registry is None) == (model is None):
        raise InvalidParameterError("give the models the drive starts with: registry or pricing.model (exactly one)",
                                    parameter=("registry", "pricing.model"))
    if battery is None:
        raise InvalidParameterError("battery is needed (its capacity, voltage, reserve and charge at the start)",
                                    parameter="battery")
    battery = check_instance("battery", battery, Battery)
    if goal is None:
        raise InvalidParameterError("goal is needed (where the drive goes)",
                                    parameter=("goal_xy_m", "goal_lonlat_deg"))
    goal = check_instance("goal", goal, MissionGoal)
    if isinstance(registry, CellModelRegistry):
        reg = registry
    elif registry is not None:
        reg = CellModelRegistry.load(registry, load_current_model, terrain=terrain)
    elif pricing.model_ground is not None:
        learned, _ = model_energy_model(terrain, model, robot_given, model_ground=pricing.model_ground,
                                        physics_ground=ground)
        reg = learned.registry
    else:
        reg = CellModelRegistry.from_terrain(terrain, model)
    nav = Navigator(terrain, reg, robot_given, battery, goal, settings=settings,
                    models=NavigatorModels(physics_ground=ground, learned=learned))
    return replace(replay_drive(nav, logs, feed=feed), map_label=map_label)
