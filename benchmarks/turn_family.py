"""Does the minimum-energy route pay for its turns? A seeded family of robots on the bundled map and procedural maps.

For each robot of a seeded random family (turn rate 0.02-2 rad/s, log-uniform; skid-steer
turning resistance, the grounds' lateral friction, 0-1; electronics 0.5-3 x the Husky's) and
each map (the bundled example map and ``--maps`` procedural maps), a few seeded queries are
planned with ``planner="lattice"`` (the heading lattice, then refinement) and compared with

- the shortest-distance route (:func:`planner.shortest_route`), priced with its turns, and
- the heading-free lattice's route (drive energy alone), priced with its turns.

The property the planner must keep: its reported energy (drive and turns) is never above
either. The table gives, per robot, the worst ratios and the mean share of turns in the
routes; the issue's case (a Husky turning at 0.02 rad/s on the bundled map, demo start and
goal) is printed on its own. Usage::

    python benchmarks/turn_family.py --out out/turn_family.json            # 8 robots x 21 maps
    python benchmarks/turn_family.py --robots 3 --maps 4 --queries 1       # a quick look
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from energy import ground_preset, robot_preset
from planner import EnergyCost, Lattice, plan_route
from planner.cost_spec import CostSpec
from planner.route import evaluate_route
from terrain import example_map, procedural_map
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M
from terrawatt_base.atomic import write_json_atomic

#: Ranges of the family (the issue's).
TURN_RATE_RANGE_RADPS = (0.02, 2.0)
LATERAL_FRICTION_RANGE = (0.0, 1.0)
ELECTRONICS_SCALE_RANGE = (0.5, 3.0)


def robot_family(seed: int) -> tuple[Any, float]:
    """Robot ``seed`` of the family and its turning resistance (the lateral friction of every ground)."""
    rng = np.random.default_rng(seed)
    husky = robot_preset("husky")
    scale = float(rng.uniform(*ELECTRONICS_SCALE_RANGE))
    lo, hi = np.log(TURN_RATE_RANGE_RADPS[0]), np.log(TURN_RATE_RANGE_RADPS[1])
    robot = husky.replace(
        name=f"family_{seed}", turn_rate_radps=float(np.exp(rng.uniform(lo, hi))),
        sensor_power_w=husky.sensor_power_w * scale, control_stable_power_w=husky.control_stable_power_w * scale,
        control_standby_power_w=husky.control_standby_power_w * scale)
    return robot, float(rng.uniform(*LATERAL_FRICTION_RANGE))


def family_cost(tmap: Any, robot: Any, lateral: float) -> EnergyCost:
    """The map priced for ``robot`` with every ground's lateral friction set to ``lateral``."""
    grounds = {name: ground_preset(name).replace(lateral_friction_coef=lateral)
               for name in sorted(set(tmap.ground_names.values()))}
    return CostSpec(robot=robot, grounds=grounds, speed_mps=0.5).build(tmap)


def _queries(cost: EnergyCost, rng: np.random.Generator, n: int) -> list[tuple[tuple[float, float], ...]]:
    free = np.argwhere(~cost.blocked)
    xc, yc = cost.terrain.cell_centres()
    out = []
    while len(out) < n:
        a, b = free[rng.choice(len(free), size=2, replace=False)]
        pa, pb = (float(xc[a[1]]), float(yc[a[0]])), (float(xc[b[1]]), float(yc[b[0]]))
        if np.hypot(pa[0] - pb[0], pa[1] - pb[1]) >= 0.3 * min(cost.shape) * cost.terrain.cell_size_m:
            out.append((pa, pb))
    return out


def _one(tmap: Any, cost: EnergyCost, start: Any, goal: Any) -> dict[str, Any] | None:
    route = plan_route(tmap, start, goal, cost=cost, planner="lattice", compare=True)
    if route.status != "exact":
        return None
    free = Lattice.for_cost(cost, 1).shortest_path(start, goal)
    free_route = evaluate_route(cost, free.waypoints_m)
    return {"energy_j": route.energy_j, "turn_j": float(np.sum(route.turn_energy_j)),
            "shortest_j": route.shortest_energy_j, "heading_free_j": free_route.energy_j,
            "heading_free_turn_j": float(np.sum(free_route.turn_energy_j)),
            "over_shortest": route.energy_j / route.shortest_energy_j,
            "over_heading_free": route.energy_j / free_route.energy_j}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=8, help="robots of the family")
    parser.add_argument("--maps", type=int, default=20, help="procedural maps (besides the bundled one)")
    parser.add_argument("--size", type=int, default=96, help="procedural map side (cells of 1 m)")
    parser.add_argument("--queries", type=int, default=2, help="start / goal pairs per map and robot")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    maps = [("example", example_map())] + [(f"procedural_{k}", procedural_map((args.size, args.size), 1.0,
                                                                               seed=args.seed + k))
                                           for k in range(args.maps)]
    rows, violations = [], []
    for r in range(args.robots):
        robot, lateral = robot_family(args.seed + r)
        results = []
        for m, (name, tmap) in enumerate(maps):
            cost = family_cost(tmap, robot, lateral)
            rng = np.random.default_rng([args.seed, r, m])
            for start, goal in _queries(cost, rng, args.queries):
                res = _one(tmap, cost, start, goal)
                if res is None:
                    continue
                res.update(robot=r, map=name, start=start, goal=goal)
                results.append(res)
                if res["over_shortest"] > 1 + 1e-9 or res["over_heading_free"] > 1 + 1e-9:
                    violations.append(res)
        rows.append({"robot": r, "turn_rate_radps": robot.turn_rate_radps, "lateral_friction": lateral,
                     "electronics_w": robot.sensor_power_w + robot.control_stable_power_w, "routes": len(results),
                     "worst_over_shortest": max(x["over_shortest"] for x in results),
                     "worst_over_heading_free": max(x["over_heading_free"] for x in results),
                     "mean_saved_vs_heading_free_pct": 100 * (1 - np.mean([x["over_heading_free"] for x in results])),
                     "turn_share_pct": 100 * float(np.mean([x["turn_j"] / x["energy_j"] for x in results])),
                     "heading_free_turn_share_pct": 100 * float(np.mean([x["heading_free_turn_j"] / x["heading_free_j"]
                                                                         for x in results]))})
        print(f"robot {r}: {rows[-1]['routes']} routes", file=sys.stderr, flush=True)
    slow = robot_preset("husky").replace(turn_rate_radps=0.02)
    tmap = example_map()
    case = _one(tmap, CostSpec(robot=slow).build(tmap), EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M)  # the presets
    print(f"{'robot':>5} {'turn rad/s':>10} {'lat. fric':>9} {'elec W':>7} {'routes':>6} {'max/shortest':>12} "
          f"{'max/heading-free':>16} {'saved %':>8} {'turns %':>8} {'free turns %':>12}")
    for row in rows:
        print(f"{row['robot']:5d} {row['turn_rate_radps']:10.3f} {row['lateral_friction']:9.2f} "
              f"{row['electronics_w']:7.1f} {row['routes']:6d} {row['worst_over_shortest']:12.4f} "
              f"{row['worst_over_heading_free']:16.4f} {row['mean_saved_vs_heading_free_pct']:8.2f} "
              f"{row['turn_share_pct']:8.2f} {row['heading_free_turn_share_pct']:12.2f}")
    if case is not None:
        print(f"\nHusky turning at 0.02 rad/s, bundled map, demo query: min-energy {case['energy_j']:.0f} J, shortest "
              f"{case['shortest_j']:.0f} J ({case['over_shortest']:.3f} x), heading-free lattice route "
              f"{case['heading_free_j']:.0f} J")
    print(f"{'MET' if not violations else 'NOT MET'} min-energy route <= shortest and <= heading-free route: "
          f"{len(violations)} violations in {sum(r['routes'] for r in rows)} routes; {time.perf_counter() - t0:.0f} s")
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "turn_family", "version": 1, "args": vars(args) | {"out": str(args.out)},
                                     "python": platform.python_version(), "robots": rows, "slow_husky_demo": case,
                                     "violations": violations}, indent=1)
        print(f"wrote {args.out}")
    return 0 if not violations else 1


if __name__ == "__main__":
    raise SystemExit(main())
