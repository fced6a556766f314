"""An independent field study of :class:`planner.Navigator`: does it learn a mislabelled patch from driven data,
and do its remaining-energy forecast and 80 % interval hold?

This is its own simulation client (it does not call :func:`planner.run_adaptive_mission`). Each
drive is a seeded scenario:

- **Maps** (flat, 1 m cells, 60-120 m square; the current models have no slope term, so a
  slope would flag cells by itself): a background ground (gravel, asphalt or concrete) and
  one or two bands of a ground the navigator's map labels ``"grass"``. The bands run across
  the whole map between start (left edge) and goal (right edge), with wobbly edges and a
  tilt (the map seed), so every route must cross them. ``"two_bands"`` puts a second band of
  the same label after the first: what the navigator learned on the first is then tested on
  the second.
- **Truth**: the robot drives a *truth* map in which the bands are another ground class with
  its own :class:`energy.GroundParams`: wet grass (the grass preset, rolling resistance x1.4-2,
  more viscous drag and slip), mud (x2-3), the sand or the snow preset (snow is cheaper than
  grass). Every ground varies along the path (:class:`energy.sim.GroundVariation`, 5 % on the
  background, 5-15 % on the patch).
- **Prior**: what a robot commissioned on the labelled grounds knows: one
  :class:`energy.LinearCurrentModel` per label (:func:`planner.missions.fit_prior_model` on the
  true background and on true grass), the grass one assigned to the band cells of the
  registry.
- **The client**: plans, then drives the navigator's current route leg by leg
  (``split_polyline`` by ``leg_length_m``; :func:`planner.simulate_mission` on the truth map, the
  log moved onto the robot's clock) and hands each leg to :meth:`Navigator.observe` in 0.5 s
  chunks (distance checkpoints; the leg's last chunk with ``checkpoint=True``). Manoeuvre
  requests are declined: with ``AdaptiveSettings(update_source="driven")`` the navigator must
  learn from what it drove.

Measured over N drives:

1. whether the navigator flags the patch (``"grass"``) and accepts a ``"driven"`` update
   (and how often it flags the background: false alarms);
2. the forecast of the remaining energy right after the first accepted update (the closing
   decision of that checkpoint) against the battery energy the robot then used to the goal
   (the navigator's ``legs[k+1:].actual_energy_j``; cross-checked against the client's own
   :class:`~planner.missions.results.MissionResult` budgets): relative error, median and p90
   (target: within 5 %);
3. coverage of the 80 % interval ``[low_j, high_j]`` at every checkpoint (the last decision
   returned for each checkpoint index that carries a forecast), pooled, by mission third
   (distance driven) and before / after the update (target 75-85 %), with the side of the
   misses;
4. the same with the in-run gain switched off (``forecast_prior_legs=1e9``: gain = 1, the
   interval only the leg-to-leg spread): the drives are identical (same seeds), only the
   forecasts differ.

Usage::

    python benchmarks/navigator_field.py                     # 50 drives, out/navigator_field.json
    python benchmarks/navigator_field.py --n 200 --seed 7 --out out/nf7.json
    python benchmarks/navigator_field.py --quick             # 8 small drives
    python benchmarks/navigator_field.py --chunk-s 1000      # one observe() per leg (the booking without chunks)

Every drive's record (checkpoints, flags, updates, legs) is in the JSON; ``summary`` holds the
table's numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from energy import Battery, GroundParams, InteractionLog, TruthSimulator, ground_preset, robot_preset
from energy.sim import VIBRATION_PRESETS, GroundVariation
from planner import AdaptiveSettings, Navigator, simulate_mission
from planner.missions import MissionDrive, NavigatorModels, fit_prior_model
from planner.missions.legs import split_polyline
from planner.registry import CellModelRegistry
from planner.route import evaluate_route
from terrain import TerrainMap
from terrawatt_base.errors import DataError

__all__ = [
    "Scenario",
    "make_scenario",
    "build_world",
    "drive",
    "summarise",
    "format_table",
    "run",
    "main",
]

LABEL = "grass"  # what the navigator's map calls the patch
BACKGROUNDS = ("gravel", "asphalt", "concrete")
TRUTH_KINDS = ("wet_grass", "mud", "sand", "snow")
LAYOUTS = ("band", "two_bands")
CHUNK_S = 0.5
LEG_LENGTH_M = 10.0
SPEED_MPS = 0.5
INTERVAL_LEVEL = 0.8
NO_GAIN_PRIOR_LEGS = 1e9  # forecast_prior_legs that makes the in-run gain 1
TARGETS = {"update_error_pct": 5.0, "coverage_pct": (75.0, 85.0)}
BUCKETS = ("first_third", "middle_third", "last_third")
PHASES = ("before_update", "after_update", "no_update")


# ======================================================================== scenarios
@dataclass(frozen=True)
class Scenario:
    """One drive: map, patch, truth ground, start and goal, seeds (all plain values)."""

    index: int
    seed: int  # seeds the navigator's settings, the truth simulator, the priors and the legs
    size: int  # map side (cells = m)
    background: str
    layout: str  # "band" or "two_bands"
    centres_m: tuple[float, ...]  # band centres along x at mid-height (m)
    widths_m: tuple[float, ...]  # band widths (m)
    tilt_rad: float  # band tilt against the y axis
    wobble_m: float  # amplitude of the edges' wobble (m)
    truth_kind: str  # one of TRUTH_KINDS
    crr_factor: float  # rolling resistance of the truth patch over grass (wet_grass / mud)
    patch_variation: float  # relative_std of the patch's ground variation
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def make_scenario(seed: int, index: int, *, quick: bool = False) -> Scenario:
    """The ``index``-th scenario of a study seeded ``seed`` (the same pair gives the same scenario)."""
    rng = np.random.default_rng([int(seed), int(index), 0xF1E1D])
    size = int(rng.choice([60, 70]) if quick else rng.choice(np.arange(60, 121, 10)))
    background = str(BACKGROUNDS[index % len(BACKGROUNDS)])
    truth_kind = str(TRUTH_KINDS[(index // len(BACKGROUNDS)) % len(TRUTH_KINDS)])
    layout = str(LAYOUTS[index % len(LAYOUTS)] if not quick else "band")
    if layout == "band":
        widths = (float(rng.uniform(0.25, 0.45) * size),)
        centres = (float(rng.uniform(0.4, 0.6) * size),)
    else:
        widths = tuple(float(w) for w in rng.uniform(0.12, 0.2, 2) * size)
        centres = (float(rng.uniform(0.28, 0.36) * size), float(rng.uniform(0.62, 0.72) * size))
    crr_factor = {"wet_grass": rng.uniform(1.4, 2.0), "mud": rng.uniform(2.0, 3.0)}.get(truth_kind, 1.0)
    margin = 0.15 * size
    start = (float(rng.uniform(3.0, 6.0)) + 0.5, float(rng.uniform(margin, size - margin)))
    goal = (size - float(rng.uniform(3.0, 6.0)) - 0.5, float(rng.uniform(margin, size - margin)))
    return Scenario(index=index, seed=int(rng.integers(0, 2**31 - 20_000)), size=size, background=background,
                    layout=layout, centres_m=centres, widths_m=widths, tilt_rad=float(rng.uniform(-0.35, 0.35)),
                    wobble_m=float(rng.uniform(0.0, 4.0)), truth_kind=truth_kind, crr_factor=float(crr_factor),
                    patch_variation=float(rng.uniform(0.05, 0.15)), start_xy_m=start, goal_xy_m=goal)


def truth_patch_ground(sc: Scenario) -> GroundParams:
    """The patch's true ground (its name is the truth map's class name)."""
    grass = ground_preset("grass")
    if sc.truth_kind == "wet_grass":
        return dataclasses.replace(grass, name="wet_grass", rolling_resistance_coef=0.10 * sc.crr_factor,
                                   viscous_friction_coef_s_per_m=0.02, longitudinal_slip_coef=0.08,
                                   lateral_slip_coef=0.08)
    if sc.truth_kind == "mud":
        return dataclasses.replace(grass, name="mud", rolling_resistance_coef=0.10 * sc.crr_factor,
                                   viscous_friction_coef_s_per_m=0.04, lateral_friction_coef=0.5,
                                   longitudinal_slip_coef=0.15, lateral_slip_coef=0.12)
    return ground_preset(sc.truth_kind)


def patch_mask(sc: Scenario) -> np.ndarray:
    """Boolean (rows, cols): the band cells (row = y, col = x, 1 m cells, origin 0)."""
    n = sc.size
    y, x = np.mgrid[0:n, 0:n] + 0.5
    rng = np.random.default_rng([sc.seed, 17])
    mask = np.zeros((n, n), bool)
    for c, w in zip(sc.centres_m, sc.widths_m):
        wob = ndimage.gaussian_filter1d(rng.standard_normal(n), sigma=6.0, mode="wrap")
        wob = sc.wobble_m * wob / max(float(np.abs(wob).max()), 1e-9)
        centre = c + np.tan(sc.tilt_rad) * (y - n / 2.0) + wob[:, None]  # along x, per row
        half = w / 2.0 + 0.5 * wob[::-1][:, None]
        mask |= np.abs(x - centre) <= half
    return mask


def build_world(sc: Scenario) -> dict[str, Any]:
    """Navigator map, truth map, truth simulator and the prior registry of a scenario."""
    robot = robot_preset("husky")
    patch = truth_patch_ground(sc)
    grounds = {sc.background: ground_preset(sc.background), LABEL: ground_preset(LABEL), patch.name: patch}
    vibration = {name: VIBRATION_PRESETS[name if name in VIBRATION_PRESETS else LABEL] for name in grounds}
    variation = {sc.background: GroundVariation(relative_std=0.05, length_scale_m=3.0),
                 patch.name: GroundVariation(relative_std=sc.patch_variation, length_scale_m=2.0)}
    truth = TruthSimulator(robot, grounds, vibration=vibration, variation=variation, seed=sc.seed)
    mask = patch_mask(sc)
    elevation = np.zeros((sc.size, sc.size))
    nav_map = TerrainMap(elevation, 1.0, ground=mask.astype(np.int16), ground_names={0: sc.background, 1: LABEL})
    truth_map = TerrainMap(elevation, 1.0, ground=np.where(mask, 2, 0).astype(np.int16),
                           ground_names={0: sc.background, 1: LABEL, 2: patch.name})
    registry = CellModelRegistry.from_terrain(nav_map, fit_prior_model(truth, sc.background, seed=sc.seed % 10_000),
                                              prior_name=f"prior-{sc.background}")
    grass_id = registry.add_model(fit_prior_model(truth, LABEL, seed=sc.seed % 10_000 + 20), name=f"prior-{LABEL}")
    registry.assign(mask, grass_id, reason=f"the map labels these cells {LABEL!r}")
    return {"robot": robot, "truth": truth, "nav_map": nav_map, "truth_map": truth_map, "registry": registry,
            "mask": mask, "patch": patch, "battery": Battery(20.0, 24.0)}


# ======================================================================== one drive
def _chunks(log: InteractionLog, chunk_s: float) -> list[InteractionLog]:
    """The log in consecutive windows of ``chunk_s`` (a short tail joins the last window)."""
    t0, t1 = float(log.time_s[0]), float(log.time_s[-1])
    edges = list(np.arange(t0, t1, chunk_s))
    if len(edges) > 1 and t1 - edges[-1] < chunk_s / 2:
        edges.pop()
    edges.append(t1 + 1e-6)
    out: list[InteractionLog] = []
    a = edges[0]
    for b in edges[1:]:
        try:
            out.append(log.slice(a, b))
            a = b
        except DataError:  # a window without a sample of one of the streams: it joins the next one
            continue
    if a < edges[-1] and out:  # the tail never made a window of its own: it joins the last one
        out[-1] = log.slice(float(out[-1].time_s[0]), edges[-1])
    return out


def drive(sc: Scenario, *, gain: bool = True, chunk_s: float = CHUNK_S) -> dict[str, Any]:
    """Drive one scenario with a Navigator (a fresh world: updates change the registry); every
    checkpoint's forecast against the energy then used to the goal.

    ``gain=False`` switches the in-run correction off (``forecast_prior_legs`` = 1e9);
    ``chunk_s`` is the driving handed to each :meth:`Navigator.observe` call.
    """
    w = build_world(sc)
    robot, truth, battery = w["robot"], w["truth"], w["battery"]
    cfg = AdaptiveSettings(update_source="driven", leg_length_m=LEG_LENGTH_M, speed_mps=SPEED_MPS,
                           interval_level=INTERVAL_LEVEL, seed=sc.seed,
                           **({} if gain else {"forecast_prior_legs": NO_GAIN_PRIOR_LEGS}))
    nav = Navigator(w["nav_map"], w["registry"], robot, battery, sc.goal_xy_m, settings=cfg,
                    models=NavigatorModels(physics_ground=ground_preset(sc.background)))
    returned = [nav.plan(sc.start_xy_m)]
    dt = 1.0 / truth.current_rate_hz
    client_legs: list[dict[str, Any]] = []  # what the client drove, leg by leg
    truth_ground = np.asarray(w["truth_map"].ground)
    declined = early_checkpoints = 0
    unbooked_s = 0.0
    while not nav.finished:
        d = returned[-1]
        if d.action == "manoeuvre":
            declined += 1
            returned.append(nav.decline_manoeuvre("the field robot does not drive manoeuvres"))
            continue
        head, _ = split_polyline(np.asarray(nav.route.waypoints_m), cfg.leg_length_m)
        leg_route = evaluate_route(nav.cost, head, status="exact", planner="leg")
        mr = simulate_mission(w["truth_map"], leg_route, robot, battery.replace(initial_soc=nav.soc), truth, nav.cost,
                              drive=MissionDrive(speed_mps=cfg.speed_mps, start_heading_rad=nav.heading_rad, stop_at_reserve=True,
                                                 seed=(sc.seed + 1000 + len(client_legs)) % 2**32))
        log = mr.log.shifted(nav.time_s + dt - float(mr.log.time_s[0]))
        rows, cols = w["truth_map"].rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
        xy = log.pose_xyh[:, :2]
        client_legs.append({"energy_j": float(mr.budget.actual_energy_j), "truth_energy_j": float(mr.truth_energy_j),
                            "length_m": float(np.hypot(*np.diff(xy, axis=0).T).sum()),
                            "on_patch": bool(np.any(truth_ground[np.asarray(rows), np.asarray(cols)] == 2))})
        chunks = _chunks(log, chunk_s)
        for i, ch in enumerate(chunks):
            last = i == len(chunks) - 1
            d = nav.observe(ch, checkpoint=True if last else None)
            returned.append(d)
            if d.checkpoint is not None and not last and not nav.finished:
                early_checkpoints += 1
            if nav.finished or d.action == "manoeuvre":
                if nav.finished:  # the robot drives on to its leg's end; the navigator books no more of it
                    unbooked_s += float(log.time_s[-1] - ch.time_s[-1])
                break
        if mr.status != "completed" and not nav.finished:
            break  # the truth run stopped short (reserve): nothing more to drive
    rec = _drive_record(sc, nav, returned, client_legs, declined, early_checkpoints, gain)
    rec["unbooked_after_arrival_s"] = unbooked_s
    return rec


def _drive_record(sc: Scenario, nav: Navigator, returned: list[Any], client_legs: list[dict[str, Any]],
                  declined: int, early_checkpoints: int, gain: bool) -> dict[str, Any]:
    legs = nav.legs
    actual = np.array([leg.actual_energy_j for leg in legs])
    after = np.concatenate((np.cumsum(actual[::-1])[::-1][1:], [0.0])) if len(legs) else np.zeros(0)  # legs k+1..
    lengths = np.array([math.hypot(leg.end_xy_m[0] - leg.start_xy_m[0], leg.end_xy_m[1] - leg.start_xy_m[1])
                        for leg in legs])
    if len(client_legs) == len(legs):  # the client's own leg lengths (polylines, not chords)
        lengths = np.array([c["length_m"] for c in client_legs])
    cum = np.cumsum(lengths) / max(float(lengths.sum()), 1e-9)
    aligned = len(client_legs) == len(legs)  # the client's legs are the navigator's (no early checkpoint)
    client = np.array([c["energy_j"] for c in client_legs]) if aligned else np.full(len(legs), np.nan)
    after_client = np.concatenate((np.cumsum(client[::-1])[::-1][1:], [0.0])) if len(legs) else np.zeros(0)
    first_update = next((u for u in nav.updates if u.accepted), None)
    first_driven = next((u for u in nav.updates if u.accepted and u.kind == "driven"), None)
    k_up = None if first_update is None else first_update.after_leg
    on_patch = [c["on_patch"] for c in client_legs] if len(client_legs) == len(legs) else [None] * len(legs)
    by_checkpoint: dict[int, Any] = {}
    for d in returned:
        if d.checkpoint is not None and d.forecast is not None:
            by_checkpoint[int(d.checkpoint)] = d  # the last decision returned for each checkpoint
    checkpoints = []
    for k, d in sorted(by_checkpoint.items()):
        if k >= len(legs):
            continue
        fc = d.forecast
        act = float(after[k])
        if act <= 0.0:
            continue
        frac = float(cum[k])
        phase = "no_update" if k_up is None else ("before_update" if k < k_up else "after_update")
        patch_ahead = bool(any(on_patch[k + 1:])) if on_patch and on_patch[0] is not None else None
        checkpoints.append({
            "checkpoint": k, "action": d.action, "position": frac,
            "bucket": BUCKETS[min(int(frac * 3.0 - 1e-9), 2)] if frac > 0 else BUCKETS[0],
            "phase": phase, "patch_ahead": patch_ahead, "forecast_j": float(fc.energy_j), "low_j": float(fc.low_j),
            "high_j": float(fc.high_j), "model_j": float(fc.model_energy_j), "gain": float(fc.gain),
            "legs_observed": int(fc.legs_observed), "actual_j": act, "error_pct": 100.0 * (fc.energy_j - act) / act,
            "covered": bool(fc.low_j <= act <= fc.high_j), "side": "in" if fc.low_j <= act <= fc.high_j else (
                "above" if act > fc.high_j else "below"),
            # against the client's own battery energy of the same legs (independent of the navigator's booking)
            "actual_client_j": float(after_client[k]), "error_client_pct": 100.0 * (fc.energy_j - after_client[k])
            / after_client[k] if aligned and after_client[k] > 0 else None,
            "covered_client": bool(fc.low_j <= after_client[k] <= fc.high_j) if aligned else None,
        })
    at_update = next((c for c in checkpoints if k_up is not None and c["checkpoint"] == k_up), None)
    flags = [(d.checkpoint, f["ground"], float(f["error_pct"])) for d in returned if d.action != "manoeuvre"
             for f in (d.evidence or {}).get("flagged", [])]  # a declined request's checkpoint closes once more
    flagged = [g for _, g, _ in flags]
    nav_total = float(actual.sum())
    client_total = float(sum(c["energy_j"] for c in client_legs))
    return {
        "index": sc.index, "gain": gain, "status": nav.status, "legs": len(legs), "client_legs": len(client_legs),
        "early_checkpoints": early_checkpoints, "declined_manoeuvres": declined,
        "flagged_patch": LABEL in flagged, "flagged_background": sc.background in flagged,
        "flag_count": {g: flagged.count(g) for g in sorted(set(flagged))},
        "flags": [{"checkpoint": k, "ground": g, "error_pct": e} for k, g, e in flags],
        "skipped": list(nav.skipped),
        "updates": [{"after_leg": u.after_leg, "ground": u.ground, "kind": u.kind, "accepted": bool(u.accepted),
                     "region_error_pct": float(u.region_error_pct),
                     "validation_error_new": float(u.validation_error_new),
                     "validation_error_old": float(u.validation_error_old)} for u in nav.updates],
        "driven_update": first_driven is not None, "driven_update_ground": None if first_driven is None else
        first_driven.ground, "first_update_leg": k_up,
        "patch_legs": [i for i, c in enumerate(client_legs) if c["on_patch"]],
        "update_forecast": at_update, "checkpoints": checkpoints,
        "energy_nav_j": nav_total, "energy_client_j": client_total,
        "booking_diff_pct": 100.0 * (nav_total - client_total) / client_total if client_total > 0 else None,
        "leg_pred_actual": [(float(leg.predicted_energy_j), float(leg.actual_energy_j)) for leg in legs],
        "client_leg_energy_j": [c["energy_j"] for c in client_legs],
    }


# ======================================================================== statistics
def _pct(x: list[float], q: float) -> float | None:
    return float(np.percentile(np.asarray(x, float), q)) if x else None


def _coverage(cps: list[dict[str, Any]]) -> dict[str, Any]:
    n = len(cps)
    if not n:
        return {"n": 0, "coverage": None, "above": None, "below": None, "median_abs_error_pct": None}
    return {"n": n, "coverage": sum(c["covered"] for c in cps) / n,
            "above": sum(c["side"] == "above" for c in cps) / n, "below": sum(c["side"] == "below" for c in cps) / n,
            "median_abs_error_pct": _pct([abs(c["error_pct"]) for c in cps], 50),
            "median_error_pct": _pct([c["error_pct"] for c in cps], 50)}


def _client_view(cps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The checkpoints scored against the client's own battery energy instead of the navigator's booking."""
    out = []
    for c in cps:
        if c["error_client_pct"] is None:
            continue
        act = c["actual_client_j"]
        side = "in" if c["covered_client"] else ("above" if act > c["high_j"] else "below")
        out.append({**c, "actual_j": act, "error_pct": c["error_client_pct"], "covered": c["covered_client"],
                    "side": side})
    return out


def _update_errors(ups: list[dict[str, Any]]) -> dict[str, Any]:
    errs = [abs(u["error_pct"]) for u in ups]
    return {"n": len(ups), "median_abs_error_pct": _pct(errs, 50), "p90_abs_error_pct": _pct(errs, 90),
            "median_error_pct": _pct([u["error_pct"] for u in ups], 50),
            "within_5pct": sum(e <= 5.0 for e in errs) / len(errs) if errs else None,
            "covered": sum(u["covered"] for u in ups) / len(ups) if ups else None}


def _variant_summary(drives: list[dict[str, Any]]) -> dict[str, Any]:
    n = len(drives)
    cps = [c for d in drives for c in d["checkpoints"]]
    ups = [d["update_forecast"] for d in drives if d["update_forecast"] is not None]
    client_cps = _client_view(cps)
    return {
        "vs_client_energy": {"update_forecast": _update_errors(_client_view(ups)), "pooled": _coverage(client_cps),
                             "by_bucket": {b: _coverage([c for c in client_cps if c["bucket"] == b]) for b in BUCKETS},
                             "by_phase": {p: _coverage([c for c in client_cps if c["phase"] == p]) for p in PHASES}},
        "rejected_updates": sum(not u["accepted"] for d in drives for u in d["updates"]),
        "drives": n,
        "completed": sum(d["status"] == "completed" for d in drives) / n if n else None,
        "flagged_patch": sum(d["flagged_patch"] for d in drives) / n if n else None,
        "driven_update": sum(d["driven_update"] for d in drives) / n if n else None,
        "flagged_background": sum(d["flagged_background"] for d in drives) / n if n else None,
        "update_forecast": _update_errors(ups),
        "coverage": {
            "pooled": _coverage(cps),
            "by_bucket": {b: _coverage([c for c in cps if c["bucket"] == b]) for b in BUCKETS},
            "by_phase": {p: _coverage([c for c in cps if c["phase"] == p]) for p in PHASES},
            "before_update_patch_ahead": _coverage([c for c in cps if c["phase"] != "after_update"
                                                    and c["patch_ahead"]]),
            "before_update_no_patch_ahead": _coverage([c for c in cps if c["phase"] != "after_update"
                                                       and c["patch_ahead"] is False]),
        },
        "all_checkpoints_abs_error_pct": {"median": _pct([abs(c["error_pct"]) for c in cps], 50),
                                          "p90": _pct([abs(c["error_pct"]) for c in cps], 90)},
        "booking_diff_pct": {"median": _pct([abs(d["booking_diff_pct"]) for d in drives
                                             if d["booking_diff_pct"] is not None], 50),
                             "max": _pct([abs(d["booking_diff_pct"]) for d in drives
                                          if d["booking_diff_pct"] is not None], 100)},
        "early_checkpoints": sum(d["early_checkpoints"] for d in drives),
        "unbooked_after_arrival_s": {"median": _pct([d["unbooked_after_arrival_s"] for d in drives], 50),
                                     "max": _pct([d["unbooked_after_arrival_s"] for d in drives], 100)},
        "declined_manoeuvres": sum(d["declined_manoeuvres"] for d in drives),
    }


def _leg_ratios(drives: list[dict[str, Any]], scenarios: list[Scenario]) -> dict[str, Any]:
    """Actual / predicted energy of legs off the patch (the background prior's own bias) and after the update."""
    off, after = [], []
    for d in drives:
        patch = set(d["patch_legs"])
        for i, (p, a) in enumerate(d["leg_pred_actual"]):
            if p <= 0 or a <= 0 or i == len(d["leg_pred_actual"]) - 1:
                continue  # the last (short) leg
            if i not in patch:
                off.append(a / p)
            elif d["first_update_leg"] is not None and i > d["first_update_leg"]:
                after.append(a / p)
    off_client = [c / p for d in drives if len(d["client_leg_energy_j"]) == len(d["leg_pred_actual"])
                  for i, ((p, _), c) in enumerate(zip(d["leg_pred_actual"][:-1], d["client_leg_energy_j"][:-1]))
                  if p > 0 and i not in set(d["patch_legs"])]
    by_bg: dict[str, list[float]] = {}
    for d, sc in zip(drives, scenarios):
        patch = set(d["patch_legs"])
        by_bg.setdefault(sc.background, []).extend(
            a / p for i, (p, a) in enumerate(d["leg_pred_actual"][:-1]) if i not in patch and p > 0)
    return {"background_legs": {"n": len(off), "median": _pct(off, 50), "p10": _pct(off, 10), "p90": _pct(off, 90),
                                "log_sd": float(np.std(np.log(off), ddof=1)) if len(off) > 1 else None},
            "background_by_ground": {k: _pct(v, 50) for k, v in by_bg.items()},
            "background_legs_client": {"n": len(off_client), "median": _pct(off_client, 50),
                                       "p10": _pct(off_client, 10), "p90": _pct(off_client, 90)},
            "patch_legs_after_update": {"n": len(after), "median": _pct(after, 50), "p10": _pct(after, 10),
                                        "p90": _pct(after, 90)}}


def summarise(drives: list[dict[str, Any]], nogain: list[dict[str, Any]] | None,
              scenarios: list[Scenario]) -> dict[str, Any]:
    out = {"with_gain": _variant_summary(drives), "leg_ratios": _leg_ratios(drives, scenarios)}
    if nogain is not None:
        out["without_gain"] = _variant_summary(nogain)
        out["identical_drives"] = all(
            [a for _, a in d["leg_pred_actual"]] == [a for _, a in e["leg_pred_actual"]]
            for d, e in zip(drives, nogain))
    by_kind: dict[str, Any] = {}
    for kind in TRUTH_KINDS:
        sel = [d for d, sc in zip(drives, scenarios) if sc.truth_kind == kind]
        if sel:
            by_kind[kind] = {"drives": len(sel), "driven_update": sum(d["driven_update"] for d in sel) / len(sel),
                             "update_forecast_median_abs_error_pct": _pct(
                                 [abs(d["update_forecast"]["error_pct"]) for d in sel if d["update_forecast"]], 50),
                             "coverage": _coverage([c for d in sel for c in d["checkpoints"]])["coverage"]}
    out["by_truth"] = by_kind
    by_layout: dict[str, Any] = {}
    for layout in LAYOUTS:
        sel = [d for d, sc in zip(drives, scenarios) if sc.layout == layout]
        if sel:
            by_layout[layout] = {"drives": len(sel), "update_forecast_median_abs_error_pct": _pct(
                [abs(d["update_forecast"]["error_pct"]) for d in sel if d["update_forecast"]], 50),
                "coverage_after_update": _coverage([c for d in sel for c in d["checkpoints"]
                                                    if c["phase"] == "after_update"])["coverage"]}
    out["by_layout"] = by_layout
    return out


# ======================================================================== report
def _f(x: Any, fmt: str = "{:.1f}", scale: float = 1.0) -> str:
    return "-" if x is None else fmt.format(x * scale)


def format_table(result: dict[str, Any]) -> str:
    s = result["summary"]
    g, ng = s["with_gain"], s.get("without_gain")
    lines = [f"navigator field study: {g['drives']} drives, seed {result['config']['seed']}, "
             f"chunks of {result['config']['chunk_s']:g} s, "
             f"wall {result['wall_time_s']:.1f} s", ""]
    lines.append(f"completed {_f(g['completed'], '{:.0%}')}; patch flagged {_f(g['flagged_patch'], '{:.0%}')}; "
                 f"driven update accepted {_f(g['driven_update'], '{:.0%}')}; background flagged "
                 f"{_f(g['flagged_background'], '{:.0%}')}; manoeuvres declined {g['declined_manoeuvres']}; "
                 f"early (distance) checkpoints {g['early_checkpoints']}; driving after arrival not booked: median "
                 f"{_f(g['unbooked_after_arrival_s']['median'])} s")
    uf = g["update_forecast"]
    lines.append(f"forecast right after the first update vs used to goal (n={uf['n']}): |err| median "
                 f"{_f(uf['median_abs_error_pct'])} %, p90 {_f(uf['p90_abs_error_pct'])} %, signed median "
                 f"{_f(uf['median_error_pct'], '{:+.1f}')} %, within 5 %: {_f(uf['within_5pct'], '{:.0%}')}, "
                 f"in its 80 % interval: {_f(uf['covered'], '{:.0%}')}   (target |err| <= 5 %)")
    uc = g["vs_client_energy"]["update_forecast"]
    lines.append(f"  the same against the client's own battery energy (n={uc['n']}): |err| median "
                 f"{_f(uc['median_abs_error_pct'])} %, p90 {_f(uc['p90_abs_error_pct'])} %, signed median "
                 f"{_f(uc['median_error_pct'], '{:+.1f}')} %, within 5 %: {_f(uc['within_5pct'], '{:.0%}')}, "
                 f"in its 80 % interval: {_f(uc['covered'], '{:.0%}')}")
    lines.append(f"update attempts rejected by validation: {g['rejected_updates']}")
    lines.append(f"navigator booking vs client's own battery energy per drive: median |diff| "
                 f"{_f(g['booking_diff_pct']['median'], '{:.3f}')} %, "
                 f"max {_f(g['booking_diff_pct']['max'], '{:.3f}')} %")
    lr = s["leg_ratios"]
    lines.append(f"actual/predicted per leg off the patch: median {_f(lr['background_legs']['median'], '{:.3f}')} "
                 f"[p10 {_f(lr['background_legs']['p10'], '{:.3f}')}, p90 {_f(lr['background_legs']['p90'], '{:.3f}')}]"
                 f", log-sd {_f(lr['background_legs']['log_sd'], '{:.3f}')}; by background "
                 + ", ".join(f"{k} {_f(v, '{:.3f}')}" for k, v in lr["background_by_ground"].items()))
    bc = lr["background_legs_client"]
    lines.append(f"  the same against the client's own battery energy: median {_f(bc['median'], '{:.3f}')} "
                 f"[p10 {_f(bc['p10'], '{:.3f}')}, p90 {_f(bc['p90'], '{:.3f}')}]")
    pa = lr["patch_legs_after_update"]
    lines.append(f"actual/predicted per patch leg after the update: median {_f(pa['median'], '{:.3f}')} "
                 f"[p10 {_f(pa['p10'], '{:.3f}')}, p90 {_f(pa['p90'], '{:.3f}')}] (n={pa['n']})")
    lines.append("")
    head = f"{'80 % interval coverage':<34}{'n':>5}  {'gain: cov':>9} {'above':>6} {'below':>6} {'|err|med':>8}"
    if ng:
        head += f"   {'no gain: cov':>12} {'above':>6} {'below':>6} {'|err|med':>8}"
    lines += [head, "-" * len(head)]

    def row(name: str, a: dict[str, Any], b: dict[str, Any] | None) -> str:
        r = (f"{name:<34}{a['n']:>5}  {_f(a['coverage'], '{:.1%}'):>9} {_f(a['above'], '{:.0%}'):>6} "
             f"{_f(a['below'], '{:.0%}'):>6} {_f(a['median_abs_error_pct'], '{:.1f}%'):>8}")
        if b is not None:
            r += (f"   {_f(b['coverage'], '{:.1%}'):>12} {_f(b['above'], '{:.0%}'):>6} {_f(b['below'], '{:.0%}'):>6} "
                  f"{_f(b['median_abs_error_pct'], '{:.1f}%'):>8}")
        return r

    c, nc = g["coverage"], (ng["coverage"] if ng else None)
    lines.append(row("pooled (target 75-85 %)", c["pooled"], nc and nc["pooled"]))
    for b in BUCKETS:
        lines.append(row(f"  {b.replace('_', ' ')} of the mission", c["by_bucket"][b], nc and nc["by_bucket"][b]))
    for p in PHASES:
        lines.append(row(f"  {p.replace('_', ' ')}", c["by_phase"][p], nc and nc["by_phase"][p]))
    lines.append(row("  not updated yet, patch ahead", c["before_update_patch_ahead"],
                     nc and nc["before_update_patch_ahead"]))
    lines.append(row("  not updated yet, no patch ahead", c["before_update_no_patch_ahead"],
                     nc and nc["before_update_no_patch_ahead"]))
    cc, ncc = g["vs_client_energy"], (ng["vs_client_energy"] if ng else None)
    lines.append(row("vs client's energy: pooled", cc["pooled"], ncc and ncc["pooled"]))
    for b in BUCKETS:
        lines.append(row(f"  {b.replace('_', ' ')} of the mission", cc["by_bucket"][b], ncc and ncc["by_bucket"][b]))
    for p in PHASES:
        lines.append(row(f"  {p.replace('_', ' ')}", cc["by_phase"][p], ncc and ncc["by_phase"][p]))
    lines.append("")
    lines.append(f"{'truth patch':<12}{'drives':>7}{'update':>8}{'|err| at update':>17}{'coverage':>10}")
    for k, v in s["by_truth"].items():
        lines.append(f"{k:<12}{v['drives']:>7}{_f(v['driven_update'], '{:.0%}'):>8}"
                     f"{_f(v['update_forecast_median_abs_error_pct'], '{:.1f} %'):>17}"
                     f"{_f(v['coverage'], '{:.0%}'):>10}")
    for k, v in s["by_layout"].items():
        lines.append(f"layout {k}: {v['drives']} drives, |err| at update median "
                     f"{_f(v['update_forecast_median_abs_error_pct'], '{:.1f} %')}, coverage after the update "
                     f"{_f(v['coverage_after_update'], '{:.0%}')}")
    if ng is not None:
        lines.append(f"drives identical with and without the gain: {s['identical_drives']}")
    return "\n".join(lines)


# ======================================================================== main
def run(n: int = 50, seed: int = 0, *, quick: bool = False, compare: bool = True,
        chunk_s: float = CHUNK_S) -> dict[str, Any]:
    """The study: ``n`` drives from seed ``seed``, with (and, with ``compare``, without) the in-run gain."""
    t0 = time.perf_counter()
    scenarios = [make_scenario(seed, i, quick=quick) for i in range(n)]
    drives, nogain = [], [] if compare else None
    for sc in scenarios:
        drives.append(drive(sc, gain=True, chunk_s=chunk_s))
        if compare:
            nogain.append(drive(sc, gain=False, chunk_s=chunk_s))
    wall = time.perf_counter() - t0
    result = {
        "config": {"n": n, "seed": seed, "quick": quick, "chunk_s": chunk_s, "leg_length_m": LEG_LENGTH_M,
                   "speed_mps": SPEED_MPS, "interval_level": INTERVAL_LEVEL, "update_source": "driven",
                   "no_gain_forecast_prior_legs": NO_GAIN_PRIOR_LEGS, "targets": TARGETS},
        "summary": summarise(drives, nogain, scenarios),
        "scenarios": [sc.to_dict() for sc in scenarios],
        "drives": drives,
        "drives_without_gain": nogain,
        "wall_time_s": wall,
        "platform": {"python": platform.python_version(), "machine": platform.machine()},
    }
    return result


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=None, help="drives (default 50; 8 with --quick)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="small maps, one band, 8 drives")
    ap.add_argument("--no-compare", action="store_true", help="skip the drives without the in-run gain")
    ap.add_argument("--chunk-s", type=float, default=CHUNK_S,
                    help="seconds of driving per observe() call (default 0.5; a large value: one chunk per leg)")
    ap.add_argument("--out", type=Path, default=Path("out/navigator_field.json"))
    args = ap.parse_args(argv)
    n = args.n if args.n is not None else (8 if args.quick else 50)
    if not args.chunk_s > 0:
        ap.error("--chunk-s must be > 0")
    result = run(n, args.seed, quick=args.quick, compare=not args.no_compare, chunk_s=args.chunk_s)
    print(format_table(result))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(_jsonable(result), indent=1))
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
