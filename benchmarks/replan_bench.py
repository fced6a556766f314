"""Replan benchmark: map preparation vs table-only refresh vs replanning after a model update.

On a seeded procedural map (1 m cells, 512^2 by default) whose cells are served by one
learned current model per ground class (a :class:`energy.LinearCurrentModel` fitted on a
simulated excitation run of that ground), the script times

(a) full map preparation from scratch: every model's table (one batched prediction each),
    the :class:`EnergyCost` and the lattice graph (the baseline, measured in the same run);
(b) the refresh after one model changed: a new model is assigned to every cell of one ground
    class, then ``LearnedEnergyModel.energy_cost(..., previous=cost)`` computes that model's
    table and reweights only the lattice edges crossing the changed cells
    (:meth:`EnergyCost.with_tables`, :meth:`Lattice.refreshed`);
(c) the replan after the refresh: the lattice search alone and ``plan_route(planner="lattice")``
    (search + route refinement), for each lattice stride.

Ratios are against (a) of the same run; numba compilation is excluded (warmed up first).
The refreshed lattice's weights are checked to equal a fresh build's exactly. Usage::

    python benchmarks/replan_bench.py --out bench_replan.json
    python benchmarks/replan_bench.py --size 256 --repeats 2      # quicker
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from energy import (
    LinearCurrentModel,
    TruthSimulator,
    excitation_commands,
    ground_preset,
    robot_preset,
)
from planner import (
    Lattice,
    LearnedEnergyModel,
    PlannerSettings,
    plan_route,
    warm_up_kernels,
)
from terrain import CellModelRegistry
from terrain.atomic import write_json_atomic
from terrain.procedural import procedural_map

GROUNDS = ("asphalt", "grass", "sand", "snow")
SPEED_MPS = 0.5


def _fit(truth: TruthSimulator, ground: str, seed: int) -> LinearCurrentModel:
    a = excitation_commands(20.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=seed)
    b = excitation_commands(8.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                            hold_s=(2.0, 3.0), rest_s=0.0, seed=seed + 1)
    logs = [truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground=ground, seed=seed + 2 + i)
            for i, p in enumerate((a, b))]
    return LinearCurrentModel().fit(logs)


def _free_point(cost: Any, frac: tuple[float, float], labels: np.ndarray, want: int) -> tuple[float, float]:
    rows, cols = cost.shape
    r0, c0 = int(frac[1] * (rows - 1)), int(frac[0] * (cols - 1))
    rr, cc = np.nonzero((~cost.blocked) & (labels == want))
    k = int(np.argmin((rr - r0) ** 2 + (cc - c0) ** 2))
    x, y = cost.terrain.xy(rr[k], cc[k])
    return (float(x), float(y))


def run(size: int, repeats: int, strides: tuple[int, ...], seed: int) -> dict[str, Any]:
    compile_s = warm_up_kernels()
    robot = robot_preset("husky")
    tmap = procedural_map((size, size), 1.0, seed=seed, grounds=GROUNDS)
    truth = TruthSimulator(robot, {g: ground_preset(g) for g in GROUNDS}, seed=seed)
    models = {g: _fit(truth, g, 10 * i + 1) for i, g in enumerate(GROUNDS)}
    updated = {g: _fit(truth, "snow" if g == "sand" else "sand", 100 + i) for i, g in enumerate(GROUNDS)}
    ground = np.asarray(tmap.ground)
    changed_ground = "sand"
    rows_out: list[dict[str, Any]] = []
    for stride in strides:
        prep, refresh, reweight, search, replan, edges = [], [], [], [], [], []
        equal = True
        for rep in range(repeats):
            reg = CellModelRegistry.from_terrain(tmap, models[GROUNDS[0]], prior_name=GROUNDS[0])
            for gi, g in enumerate(GROUNDS[1:], 1):
                reg.assign(np.nonzero(ground == gi), reg.add_model(models[g], name=g))
            # (a) preparation from scratch: tables of every model, EnergyCost, lattice graph
            t0 = time.perf_counter()
            lem = LearnedEnergyModel(reg, robot, ground_preset("asphalt"))
            cost = lem.energy_cost(tmap, SPEED_MPS)
            lat = Lattice.for_cost(cost, stride)
            prep.append(time.perf_counter() - t0)
            labels = cost.components()
            main = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
            start = _free_point(cost, (0.05, 0.3), labels, main)
            goal = _free_point(cost, (0.95, 0.7), labels, main)
            # (b) one model changes: a new model on every cell of one ground class
            gid = GROUNDS.index(changed_ground)
            mid = reg.add_model(updated[changed_ground], name=f"{changed_ground}-update{rep}")
            reg.assign(np.nonzero(ground == gid), mid)
            t0 = time.perf_counter()
            cost2 = lem.energy_cost(tmap, SPEED_MPS, previous=cost)
            refresh.append(time.perf_counter() - t0)
            lat2 = Lattice.for_cost(cost2, stride)
            reweight.append(lat2.build_time_s)
            edges.append((lat2.edges_computed, lat.edges_computed, int(cost2.changed_cells.sum())))
            # (c) replan after the refresh
            t0 = time.perf_counter()
            path = lat2.shortest_path(start, goal)
            search.append(time.perf_counter() - t0)
            settings = PlannerSettings(lattice_stride_cells=stride)
            t0 = time.perf_counter()
            route = plan_route(tmap, start, goal, cost=cost2, planner="lattice", compare=False, settings=settings)
            replan.append(time.perf_counter() - t0)
            if rep == 0:  # exactness check against a fresh build (not timed)
                fresh = Lattice(LearnedEnergyModel(reg, robot, ground_preset("asphalt")).energy_cost(tmap, SPEED_MPS),
                                stride)
                g_fresh, g_new = fresh.graph("energy"), lat2.graph("energy")
                equal = bool(np.array_equal(g_fresh.data, g_new.data) and np.array_equal(g_fresh.indices, g_new.indices)
                             and np.array_equal(g_fresh.indptr, g_new.indptr))
                found = path.found and route.found
        med = {k: statistics.median(v) for k, v in (("prep_s", prep), ("refresh_s", refresh), ("reweight_s", reweight),
                                                     ("search_s", search), ("plan_route_s", replan))}
        rows_out.append({
            "stride_cells": stride,
            **med,
            "refresh_plus_search_s": med["refresh_s"] + med["search_s"],
            "refresh_plus_plan_route_s": med["refresh_s"] + med["plan_route_s"],
            "refresh_over_prep": med["refresh_s"] / med["prep_s"],
            "replan_over_prep": (med["refresh_s"] + med["plan_route_s"]) / med["prep_s"],
            "changed_cells": edges[0][2],
            "edges_recomputed": edges[0][0],
            "edges_total": edges[0][1],
            "weights_equal_fresh_build": equal,
            "route_found": found,
        })
    return {
        "benchmark": "replan",
        "map_cells": [size, size],
        "seed": seed,
        "repeats": repeats,
        "changed_ground": changed_ground,
        "models": len(GROUNDS),
        "numba_warm_up_s": compile_s,
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count(), "platform": platform.platform()},
        "target_replan_s": 0.2,
        "results": rows_out,
    }


def _print(res: dict[str, Any]) -> None:
    print(f"replan benchmark: {res['map_cells'][0]}^2 cells, {res['models']} models, '{res['changed_ground']}' "
          f"model replaced, median of {res['repeats']}")
    cols = ("stride_cells", "prep_s", "refresh_s", "reweight_s", "search_s", "plan_route_s",
            "refresh_plus_plan_route_s", "refresh_over_prep", "replan_over_prep", "edges_recomputed", "edges_total",
            "weights_equal_fresh_build")
    print(" ".join(f"{c:>14.14s}" for c in cols))
    for r in res["results"]:
        print(" ".join(f"{r[c]:>14.4f}" if isinstance(r[c], float) else f"{r[c]!s:>14}" for c in cols))


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="map side in cells (default 512)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--strides", type=int, nargs="+", default=[1, 2], help="lattice strides (cells)")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None, help="write the results as JSON here")
    args = parser.parse_args(argv)
    res = run(args.size, args.repeats, tuple(args.strides), args.seed)
    _print(res)
    if args.out is not None:
        write_json_atomic(args.out, res, indent=1)
    return res


if __name__ == "__main__":
    main()
