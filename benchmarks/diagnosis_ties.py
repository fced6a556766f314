"""Ties and their separating drives, closed on the independent simulator: named, driven, settled.

Each pair is a case where the diagnosed runs cannot tell the true cause from a look-alike:

- ``payload_vs_turning``: the robot 30 kg heavier than its calibration runs, on turning-heavy
  driving (arcs and pivots), the robot itself with a turning resistance (Wong's law,
  ``turning_mu_max`` 0.4) in the calibration runs too. A payload raises every mass term,
  the turning moment among them, so a larger lateral friction fits the turns about as well.
  The truth: ``mass`` (mass scale - 1 = 0.6).
- ``gain_vs_offset``: the left current sensor reading 25 % high, on runs at one speed
  (``"cruise"``) cropped to the cruising part (above 90 % of that speed: no rests, no starts):
  at one current, a gain and an offset are the same. The truth: ``current_gain`` (gain_left / gain_right - 1 = 0.25).

- ``mass_vs_rolling``: the robot 30 kg heavier than its calibration runs, on runs at one speed
  cropped to the cruising part (as ``gain_vs_offset``: no starts, whose inertia would show the
  mass) across the level part of a map with a 10° ramp (:func:`slope_map`, the independent
  simulator's :data:`SLOPE`): on level ground a payload scales the rolling resistance and
  nothing else, so a larger rolling resistance (or an idle current, or an offset: at one speed
  all are one constant) fits as well; uphill, gravity scales with the mass and not with the
  rolling resistance. The diagnosis is
  given the map (the model calibrated on level runs is put on it), so its separating drive
  may go up and back down the ramp; the drive is simulated where the diagnosis placed it.
  The truth: ``mass`` (mass scale - 1 = 0.6).
- ``inertia_vs_lag``: the drivetrain's rotating parts 3 times heavier than in the calibration runs
  (the simulator's ``rotor_inertia_scale``), on ``"waves"`` driving (straight, no stops, the speed
  swelling and easing between ~0.3 and ~0.9 m/s over 8-11 s) cropped above 0.2 m/s, the robot itself
  with a speed-squared drag (:data:`DRAG_N_S2_PER_M2`) in the calibration runs too, which are waves
  as well and fit the viscous coefficient besides the defaults. Where the current grows with the
  speed its slope follows the acceleration, so a current lag (the currents leading, ``-tau dI/dt``)
  adds what a heavier drivetrain adds (``m_rot a``), up to the model's own inertia term shifted; a
  stop and a start part them. The truth: ``rotor_inertia``, its value the simulator's rotating
  parts at the motor shaft as the library charges them (:func:`independent_sim.rotor_inertia_kg_m2`, kg m^2).

- ``lag_vs_inertia``: the other direction of ``inertia_vs_lag``: the robot's drivetrain 3 times heavier
  before and after (calibration runs and the model's rotor inertia both know it), and its currents'
  stamps running :data:`CURRENT_LAG_S` late against the speeds in the diagnosed runs (the simulator's
  ``current_lag_s``). A lag of the currents (``-tau dI/dt``) takes off what a lighter drivetrain
  takes off. The truth: ``time_lag`` (``lag_s`` = :data:`CURRENT_LAG_S`).

Protocol per pair and seed: 6 calibration runs of the robot before the change (mixed
driving unless the pair says) fit ``PhysicsCurrentModel(sim.husky_robot(), "flooring")`` (the Husky
preset with the simulator's drivetrain inertia, :func:`independent_sim.husky_robot`); 6 diagnosed runs with the change;
``diagnose`` (the library call ``terrawatt diagnose`` makes). Recorded: whether a tie holding
the truth is named, the separating drive (duration, its smallest expected difference in A and
in noise units, its separation per run ``z``, the runs it asks for), then that drive simulated
by the independent simulator with the change, as many runs as asked (at most ``--max-repeats``),
the measured difference on the first against the expected one, and the diagnosis again with
those runs added to the data: the truth first, its fitted value within 20 %, a tie left. The
expected difference is given per drive (``z``: over the whole drive, against the noise of that
whole-drive quantity, the residual's correlation and the run-to-run spread counted) and per sample
(``x noise``: the RMS difference over the sensor's white noise).

For a pair on a map, the difference is also given in noise units over the drive's samples on
the ramp (``noise_units_ramp``), where the two explanations part.

Usage::

    python benchmarks/diagnosis_ties.py --seeds 10 --out out/diagnosis_ties.json
    python benchmarks/diagnosis_ties.py --quick
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import energy
from energy.diagnosis import diagnose
from terrain import TerrainMap
from terrawatt_base.atomic import write_json_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/ is no package: its siblings by path
import independent_sim as sim  # noqa: E402

#: The ramp of the map pairs: rising 10° along +x from x = 70 m to 90 m, a plateau beyond (the manoeuvres
#: the diagnosis places near the map's centre, 20 m from its foot, drive on level ground).
SLOPE = sim.Slope(math.radians(10.0), start_m=70.0, length_m=20.0)
#: The map's extent (m, from the origin) and cell size: room for a straight run of 90 s along +y.
MAP_EXTENT_M = (100.0, 100.0)
MAP_CELL_M = 1.0


def slope_map() -> TerrainMap:
    """The independent simulator's :data:`SLOPE` as the map the diagnosis is given: its elevation at the
    cell centres over :data:`MAP_EXTENT_M`, flooring everywhere."""
    cols, rows = (int(round(e / MAP_CELL_M)) for e in MAP_EXTENT_M)
    x = (np.arange(cols) + 0.5) * MAP_CELL_M
    y = (np.arange(rows) + 0.5) * MAP_CELL_M
    xx, yy = np.meshgrid(x, y)
    return TerrainMap(SLOPE.elevation_m(xx, yy), MAP_CELL_M, ground=np.zeros((rows, cols), np.int16),
                      ground_names={0: "flooring"})


def _level_start(k: int) -> tuple[float, float, float]:
    """Where diagnosed run ``k`` of a map pair starts: on the level part, heading +y (along the contour)."""
    return 5.0 + 3.0 * k, 5.0, math.pi / 2


#: The pairs: calibration effects, diagnosed effects, driving, the speed above which the runs are
#: kept (None: whole runs), the catalogue effects that are the truth, how to read its size and the size;
#: ``slope``: the runs and the drive on the ramp's map (the diagnosed runs start at ``_level_start``).
PAIRS: dict[str, dict[str, Any]] = {
    "payload_vs_turning": {
        "calibration": sim.SimEffects(turning_mu_max=0.4),
        "diagnosed": sim.SimEffects(turning_mu_max=0.4, payload_kg=30.0),
        "driving": "turning", "crop": None, "truth": ("mass",),
        "value": ("mass_scale", 30.0 / sim.MASS_KG),
    },
    "gain_vs_offset": {
        "calibration": sim.SimEffects(),
        "diagnosed": sim.SimEffects(left_gain=1.25),
        "driving": "cruise", "crop": 0.9 * sim.CRUISE_SPEED_MPS, "truth": ("current_gain",),
        "value": ("gain_ratio", 0.25),
    },
    "mass_vs_rolling": {
        "calibration": sim.SimEffects(),
        "diagnosed": sim.SimEffects(payload_kg=30.0),
        "driving": "cruise", "crop": 0.9 * sim.CRUISE_SPEED_MPS, "truth": ("mass",),
        "value": ("mass_scale", 30.0 / sim.MASS_KG), "slope": SLOPE,
    },
}
#: The speed-squared resistance of the robot of ``inertia_vs_lag`` (N s^2 / m^2 per side, before and after
#: the change): the current grows with the speed, so its slope follows the acceleration.
DRAG_N_S2_PER_M2 = 20.0
#: How much heavier the drivetrain of ``inertia_vs_lag`` is (the independent simulator's ``rotor_inertia_scale``).
ROTOR_SCALE = 3.0


PAIRS["inertia_vs_lag"] = {
    "calibration": sim.SimEffects(speed_friction_n_s2_per_m2=DRAG_N_S2_PER_M2),
    "diagnosed": sim.SimEffects(speed_friction_n_s2_per_m2=DRAG_N_S2_PER_M2, rotor_inertia_scale=ROTOR_SCALE),
    "driving": "waves", "calibration_driving": "waves", "crop": 0.2, "truth": ("rotor_inertia",),
    "fit": ("rolling_resistance_coef", "lateral_friction_coef", "rest_current_a", "viscous_friction_coef_s_per_m"),
    "value": ("rotor_inertia_kg_m2", sim.rotor_inertia_kg_m2(ROTOR_SCALE)),
}
#: The current lag of ``lag_vs_inertia`` (s: the currents' stamps run late against the speeds).
CURRENT_LAG_S = 0.2
PAIRS["lag_vs_inertia"] = {
    "calibration": sim.SimEffects(speed_friction_n_s2_per_m2=DRAG_N_S2_PER_M2, rotor_inertia_scale=ROTOR_SCALE),
    "diagnosed": sim.SimEffects(speed_friction_n_s2_per_m2=DRAG_N_S2_PER_M2, rotor_inertia_scale=ROTOR_SCALE,
                                current_lag_s=CURRENT_LAG_S),
    "driving": "waves", "calibration_driving": "waves", "crop": 0.2, "truth": ("time_lag",),
    "fit": PAIRS["inertia_vs_lag"]["fit"], "rotor_scale": ROTOR_SCALE,
    "value": ("lag_s", CURRENT_LAG_S),
}
TARGETS = {"tie_named_pct": 100.0, "truth_first_after_pct": 90.0, "value_ok_after_pct": 90.0,
           "drive_max_s": 60.0, "z_min": 3.0, "measured_over_expected": (0.5, 2.0)}
VALUE_TOL = 0.2
RUNS = 6


def _moving_part(log: Any, speed: float = 0.3) -> Any:
    """The log from its first to its last sample faster than ``speed`` (the rests cut off)."""
    fast = np.nonzero(np.abs(log.v_mps) > speed)[0]
    return log.slice(float(log.time_s[fast[0]]), float(log.time_s[fast[-1]]))


def _value(d: Any, how: str, model: Any) -> float | None:
    """The fitted size of the truth's effect in ``d`` (first chosen) of ``model``, as ``how`` reads it."""
    if not d.current.chosen:
        return None
    p = d.current.score(d.current.chosen[0]).parameters
    if how == "mass_scale" and "mass_scale" in p:
        return p["mass_scale"] - 1.0
    if how == "gain_ratio" and {"gain_left", "gain_right"} <= set(p):
        return p["gain_left"] / p["gain_right"] - 1.0
    if how == "lag_s" and "lag_s" in p:
        return p["lag_s"]
    if how == "rotor_inertia_kg_m2" and "rotor_inertia_scale" in p:
        return p["rotor_inertia_scale"] * model.robot_.motor.rotor_inertia_kg_m2
    return None


def run_pair(name: str, seed: int, max_repeats: int) -> dict[str, Any]:
    """One pair, one seed: the diagnosis, its separating drive, the drive simulated, the diagnosis again."""
    pair = PAIRS[name]
    cal = [sim.simulate_run(50_000 + 1000 * seed + k, pair["calibration"], driving=pair.get("calibration_driving", "mixed"))
           for k in range(RUNS)]
    robot = sim.husky_robot()
    if "rotor_scale" in pair:  # a user who knows the robot's heavier drivetrain gives it to the model
        heavier = sim.rotor_inertia_kg_m2(pair["rotor_scale"])
        robot = robot.replace(motor=dataclasses.replace(robot.motor, rotor_inertia_kg_m2=heavier))
    model = energy.PhysicsCurrentModel(robot, "flooring",
                                       **({"fit_parameters": pair["fit"]} if "fit" in pair else {})).fit(cal)
    slope = pair.get("slope")
    terrain = None if slope is None else slope_map()
    if terrain is not None:
        model = model.with_terrain(terrain)  # calibrated on level runs, put on the map the runs drive
    logs = [sim.simulate_run(10_000 + 1000 * seed + k, pair["diagnosed"], driving=pair["driving"], slope=slope,
                             start_pose=None if slope is None else _level_start(k)) for k in range(RUNS)]
    if pair["crop"] is not None:
        logs = [_moving_part(log, pair["crop"]) for log in logs]
    t0 = time.perf_counter()
    d = diagnose(model, logs, terrain=terrain)
    row: dict[str, Any] = {"pair": name, "seed": seed, "diagnose_s": time.perf_counter() - t0,
                           "chosen": list(d.current.chosen), "ties": [t.to_dict() for t in d.ties]}
    truth = set(pair["truth"])
    tie = next((t for t in d.ties if truth & set(t.effects)), None)
    row["tie_named"] = tie is not None
    row["truth_first_before"] = bool(d.current.chosen) and d.current.chosen[0] in truth
    drive = next((x for x in d.separating_drives if tie is not None and x.effects == tie.effects), None)
    row["drive"] = None if drive is None else {
        "description": drive.best.description, "duration_s": drive.best.duration_s, "repeats": drive.repeats,
        "expected_difference_a": drive.expected_difference_a, "noise_a": drive.noise_a,
        "noise_units": drive.noise_units, "equivalent": list(drive.equivalent),
        "z_min": min((p.z_per_repeat for p in drive.separated.values()), default=None)}  # x noise per drive
    if drive is not None and slope is not None and drive.separated:
        row["drive"]["noise_units_ramp"] = _noise_units_on(drive, slope)
    if drive is None or not drive.separated:
        return row
    n = min(max(drive.repeats, 1), max_repeats)
    start = None if drive.profile.pose_xyh is None else tuple(drive.profile.pose_xyh[0])
    runs = [sim.simulate_run(70_000 + 1000 * seed + r, pair["diagnosed"], commands=drive.profile, slope=slope,
                             start_pose=start if slope is not None else None) for r in range(n)]
    scores = drive.score(runs[0])
    row["measured_over_expected"] = {alt: scores[alt]["measured_difference_a"] / drive.best.pairs[alt].difference_rms_a
                                     for alt in drive.separated}
    row["projection"] = {alt: scores[alt]["projection"] for alt in drive.separated}
    row["drive_runs"] = n
    after = diagnose(model, logs + runs, terrain=terrain)
    row["chosen_after"] = list(after.current.chosen)
    row["truth_first_after"] = bool(after.current.chosen) and after.current.chosen[0] in truth
    row["tie_after"] = any(truth & set(t.effects) for t in after.ties)
    how, size = pair["value"]
    value = _value(after, how, model) if row["truth_first_after"] else None
    row["value_after"] = {"fitted": value, "truth": size}
    row["value_ok_after"] = value is not None and abs(value / size - 1.0) <= VALUE_TOL
    return row


def _noise_units_on(drive: Any, slope: Any) -> float | None:
    """The drive's smallest difference of a separable pair in noise units over its samples on the ramp
    (None: none of them is)."""
    pose = drive.profile.pose_xyh
    if pose is None:
        return None
    on = slope.on_ramp(pose[:, 0], pose[:, 1])
    if not on.any():
        return None
    chosen = drive.predictions[drive.effects[0]]
    return min(float(np.sqrt(np.mean((drive.predictions[alt][on] - chosen[on]) ** 2))) / drive.noise_a
               for alt in drive.separated)


def _pct(flags: list[bool]) -> float | None:
    return 100.0 * sum(flags) / len(flags) if flags else None


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per pair: tie named %, truth first after the drive %, value within 20 % %, drive length, z,
    measured / expected."""
    out = {}
    for name in dict.fromkeys(r["pair"] for r in rows):
        sel = [r for r in rows if r["pair"] == name]
        driven = [r for r in sel if "truth_first_after" in r]
        ratios = [v for r in driven for v in r["measured_over_expected"].values()]
        out[name] = {
            "seeds": len(sel),
            "tie_named_pct": _pct([r["tie_named"] for r in sel]),
            "truth_first_before_pct": _pct([r["truth_first_before"] for r in sel]),
            "driven": len(driven),
            "truth_first_after_pct": _pct([r["truth_first_after"] for r in driven]),
            "value_ok_after_pct": _pct([r["value_ok_after"] for r in driven]),
            "tie_left_after_pct": _pct([r["tie_after"] for r in driven]),
            "drive_s_max": max((r["drive"]["duration_s"] for r in driven), default=None),
            "runs_median": statistics.median([r["drive_runs"] for r in driven]) if driven else None,
            "z_min": min((r["drive"]["z_min"] for r in driven), default=None),
            "z_median": statistics.median([r["drive"]["z_min"] for r in driven]) if driven else None,
            "noise_units_median": statistics.median([r["drive"]["noise_units"] for r in driven]) if driven else None,
            "noise_units_ramp_range": _range([r["drive"].get("noise_units_ramp") for r in driven]),
            "measured_over_expected_range": (min(ratios), max(ratios)) if ratios else None,
        }
    return out


def _range(values: list[float | None]) -> tuple[float, float] | None:
    got = [v for v in values if v is not None]
    return (min(got), max(got)) if got else None


def _f(x: Any, fmt: str = ".1f") -> str:
    return "–" if x is None else format(x, fmt)


def table(summary: dict[str, Any]) -> str:
    """The summary as a text table."""
    head = (f"{'pair':<20} {'seeds':>5} {'tie named %':>11} {'1st before %':>12} {'driven':>6} {'1st after %':>11} "
            f"{'value ok %':>10} {'tie left %':>10} {'drive s':>7} {'runs':>4} {'z min':>6} {'z med':>6} "
            f"{'x noise':>7} "
            f"{'meas/exp':>11} {'x noise ramp':>12}")
    lines = [head, "-" * len(head)]
    for name, s in summary.items():
        rng, ramp = s["measured_over_expected_range"], s["noise_units_ramp_range"]
        lines.append(f"{name:<20} {s['seeds']:>5} {_f(s['tie_named_pct']):>11} {_f(s['truth_first_before_pct']):>12} "
                     f"{s['driven']:>6} {_f(s['truth_first_after_pct']):>11} {_f(s['value_ok_after_pct']):>10} "
                     f"{_f(s['tie_left_after_pct']):>10} {_f(s['drive_s_max']):>7} {_f(s['runs_median'], '.0f'):>4} "
                     f"{_f(s['z_min']):>6} {_f(s['z_median']):>6} {_f(s['noise_units_median'], '.2f'):>7} "
                     f"{'–' if rng is None else f'{rng[0]:.2f}-{rng[1]:.2f}':>11} "
                     f"{'–' if ramp is None else f'{ramp[0]:.2f}-{ramp[1]:.2f}':>12}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0,
                    help="the first seed (default 0): seeds first-seed ... first-seed + seeds - 1")
    ap.add_argument("--pairs", nargs="+", default=list(PAIRS), choices=list(PAIRS))
    ap.add_argument("--max-repeats", type=int, default=10, help="most runs of a drive simulated (default 10)")
    ap.add_argument("--quick", action="store_true", help="two seeds")
    ap.add_argument("--out", type=Path, default=None, help="write the rows and the summary as JSON here")
    args = ap.parse_args(argv)
    seeds = 2 if args.quick else args.seeds
    t0 = time.perf_counter()
    rows = [run_pair(name, seed, args.max_repeats) for name in args.pairs
            for seed in range(args.first_seed, args.first_seed + seeds)]
    summary = summarise(rows)
    print(table(summary))
    print(f"targets: tie named before the drive, truth first after it >= 90 %, value within 20 % >= 90 %, drive "
          f"<= 60 s, z >= 3 per run (z: the whole drive's expected difference over that quantity's noise, the "
          f"residual's correlation and the run-to-run spread counted; 'x noise': the same per sample over the "
          f"sensor's white noise, median), measured / expected difference within 0.5-2; {len(rows)} diagnoses pairs in "
          f"{time.perf_counter() - t0:.0f} s")
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "diagnosis_ties", "targets": TARGETS, "value_tolerance": VALUE_TOL,
                                     "runs": RUNS, "seeds": seeds, "first_seed": args.first_seed,
                                     "summary": summary, "rows": rows,
                                     "machine": {"python": platform.python_version(),
                                                 "platform": platform.platform()}}, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
