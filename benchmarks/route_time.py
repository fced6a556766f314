"""A route's time against the mission simulator's: the old formula, the stop-turn-go rule, the simulator's log.

On the fixed routes of ``sim_gap.py`` (flat and over the hills, a right angle, a U-turn, the hills tour and the golden
``tour_chargers`` shed segment) this prints, per route, the duration the planner reported before the stop-turn-go
rule (surface length at the speed plus the heading changes at the turn rate), the one it reports now
(:func:`planner.route_time.route_duration_s`, what :attr:`planner.Route.duration_s` holds) and the time the mission
simulator's log lasts driving the route (a noise-free :class:`energy.TruthSimulator` of the robot the cost prices,
no velocity lag, sampled at 100 Hz: the log ends at the first sample at or after the profile's end).

Usage::

    python benchmarks/route_time.py --out route_time.json
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
import sim_gap  # the routes (benchmarks/ is the script's directory)

from energy import Battery, TruthSimulator, ground_preset, robot_preset
from energy.sim import NoiseModel
from planner import CostSpec, simulate_mission
from planner.missions.options import MissionDrive
from planner.route import evaluate_route
from terrawatt_base.atomic import write_json_atomic

SPEED_MPS = 0.5
RATE_HZ = 100.0


def times(tmap: Any, wp: np.ndarray) -> dict[str, float]:
    """The old duration, the route's (the stop-turn-go rule) and the simulator's driven time (s) of ``wp``."""
    robot = robot_preset("husky")
    cost = CostSpec(robot=robot, speed_mps=SPEED_MPS).build(tmap)
    route = evaluate_route(cost, wp)
    angles, _ = cost.turn_energies_j(route.waypoints_m)
    old = cost.surface_length_m(route.waypoints_m) / cost.speed_mps + float(angles.sum()) / cost.turn_rate_radps
    grounds = {n: ground_preset(n) for n in set(tmap.ground_names.values())}
    sim = TruthSimulator(robot, grounds, noise=NoiseModel.off(), velocity_time_constant_s=0.0,
                         current_rate_hz=RATE_HZ, seed=0)
    m = simulate_mission(tmap, route, robot, Battery(20.0, 24.0), sim, cost,
                         drive=MissionDrive(speed_mps=SPEED_MPS, seed=0))
    t = np.asarray(m.time_s)
    return {"old_s": old, "route_s": route.duration_s, "simulator_s": float(t[-1] - t[0]),
            "sample_s": 1.0 / RATE_HZ, "stops": int(np.count_nonzero(route.turn_energy_j[1:-1] > 0))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    rows = {name: times(tmap, wp) for name, (tmap, wp) in sim_gap.routes().items()}
    print(f"{'route':38s} {'stops':>5s} {'before (s)':>10s} {'now (s)':>9s} {'simulator (s)':>13s} {'now - sim':>9s}")
    for name, r in rows.items():
        print(f"{name:38s} {r['stops']:5d} {r['old_s']:10.2f} {r['route_s']:9.2f} {r['simulator_s']:13.2f} "
              f"{r['route_s'] - r['simulator_s']:9.3f}")
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "route_time", "speed_mps": SPEED_MPS, "rate_hz": RATE_HZ,
                                     "routes": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
