"""Replan benchmark: map preparation vs table-only refresh vs replanning (full or incremental) after a model update.

On a seeded procedural map (1 m cells, 512^2 by default) whose cells are served by one
learned current model per ground class (a :class:`energy.LinearCurrentModel` fitted on a
simulated excitation run of that ground), the script times, for each lattice stride,

(a) full map preparation from scratch: every model's table (one batched prediction each),
    the :class:`EnergyCost` and the lattice graph (the baseline, measured in the same run),
    and a search from scratch (``Lattice.shortest_path``, A*); the incremental planner's
    first search (:class:`planner.IncrementalPlanner` with ``heading=False``, D* Lite from the
    goal) is timed too. These are the heading-free searches (drive energy alone); the heading
    lattice's (drive and turns: ``heading=True``, the default, and ``plan_route(planner="lattice")``)
    are timed beside them: a search from scratch (:func:`heading_shortest_path`) and the
    replanner's first search;
(b) two model updates, one after the other:

    - ``patch``: a new model on a 20 x 20 cell patch across the middle of the current route;
    - ``class``: a new model on every cell of the 'sand' class (~68 k cells at 512^2);

    each refreshed with ``LearnedEnergyModel.energy_cost(..., previous=cost)`` (the new
    model's table, and only the lattice edges crossing changed cells are reweighted:
    :meth:`EnergyCost.with_tables`, :meth:`Lattice.refreshed`, which lists the changed moves);
(c) the replan after each update: the incremental planner's ``update`` (marks the nodes whose
    moves changed) and ``plan`` (repairs the previous search from the same start), side by
    side with a search from scratch on the refreshed lattice and ``plan_route(planner="lattice")``
    (search + route refinement).

The heading replanner keeps its heuristic (lowered where moves got cheaper) and its
workspace; after each update its ``heading_update_s`` + ``heading_repair_s`` (a search) are set
against a heading search from scratch on the refreshed lattice, whose energy it must equal.

``incremental_s`` = refresh + update + repair; ``speedup_vs_scratch`` = (preparation + search
from scratch) / ``incremental_s``; ``speedup_vs_full_replan`` = (refresh + search from
scratch) / ``incremental_s``. The incremental energy is checked against the search from
scratch (relative difference), and the refreshed lattice's weights against a fresh build
(exactly). Medians over the repeats; numba compilation is excluded (warmed up first); the
load average is recorded (the machine may be shared). Usage::

    python benchmarks/replan_bench.py --out bench_replan.json
    python benchmarks/replan_bench.py --size 256 --repeats 2 --strides 1      # quicker
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
    CostTables,
    EnergyCost,
    IncrementalPlanner,
    Lattice,
    LearnedEnergyModel,
    PlannerSettings,
    plan_route,
    warm_up_kernels,
)
from planner.heading_lattice import heading_shortest_path
from planner.kernels import graph
from planner.registry import CellModelRegistry
from terrain import TerrainMap
from terrain.procedural import procedural_map
from terrawatt_base.atomic import write_json_atomic

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


def _warm_up() -> float:
    """Compile (or load) every kernel, the incremental search's and the banded refresh's included."""
    t0 = time.perf_counter()
    warm_up_kernels()
    tmap = TerrainMap(np.zeros((6, 6)), 1.0)
    cost = EnergyCost(tmap, np.zeros((6, 6), np.int32), CostTables(np.ones((1, 3)), np.ones((1, 2))), speed_mps=1.0, battery_voltage_v=1.0, turn_rate_radps=1.0)
    planner = IncrementalPlanner(Lattice.for_cost(cost, 1), (5.5, 5.5), heading=False)
    planner.plan((0.5, 0.5))
    planner.replan((0.5, 1.5), Lattice.for_cost(cost.with_tables(CostTables(2.0 * cost.tables.grade_table_j_per_m, cost.tables.turn_table_j)), 1))
    arr, half = cost.arrays, np.array([(0, 1), (1, 0)], dtype=np.int64)
    sat, pos = np.zeros((7, 7), dtype=np.int32), np.full((36, 4), -1, dtype=np.int32)
    for kernel in (graph.lattice_reweight_serial, graph.lattice_reweight_parallel):
        kernel(arr.cells, arr.grade_table, arr.geo, 1, 0, 6, 6, half, sat, pos, np.zeros(0), 0, 6, 0, 6, 0)
    return time.perf_counter() - t0


def _patch(cost: Any, waypoints_m: np.ndarray, side: int) -> np.ndarray:
    """A ``side`` x ``side`` cell mask centred on the route's middle waypoint."""
    mid = waypoints_m[len(waypoints_m) // 2]
    r, c = (int(v) for v in cost.terrain.rowcol(mid[0], mid[1]))
    mask = np.zeros(cost.shape, bool)
    r0 = min(max(r - side // 2, 0), cost.shape[0] - side)
    c0 = min(max(c - side // 2, 0), cost.shape[1] - side)
    mask[r0:r0 + side, c0:c0 + side] = True
    return mask


SCENARIOS = ("patch", "class")


def run(size: int, repeats: int, strides: tuple[int, ...], seed: int, patch_cells: int = 20) -> dict[str, Any]:
    load_before = os.getloadavg()
    compile_s = _warm_up()
    robot = robot_preset("husky")
    tmap = procedural_map((size, size), 1.0, seed=seed, grounds=GROUNDS)
    truth = TruthSimulator(robot, {g: ground_preset(g) for g in GROUNDS}, seed=seed)
    models = {g: _fit(truth, g, 10 * i + 1) for i, g in enumerate(GROUNDS)}
    updated = {g: _fit(truth, "snow" if g == "sand" else "sand", 100 + i) for i, g in enumerate(GROUNDS)}
    ground = np.asarray(tmap.ground)
    changed_ground = "sand"
    rows_out: list[dict[str, Any]] = []
    for stride in strides:
        base: dict[str, list[float]] = {k: [] for k in ("prep_s", "scratch_search_s", "incremental_first_s",
                                                          "heading_scratch_s", "heading_first_s")}
        per: dict[str, dict[str, list[Any]]] = {sc: {} for sc in SCENARIOS}
        for rep in range(repeats):
            reg = CellModelRegistry.from_terrain(tmap, models[GROUNDS[0]], prior_name=GROUNDS[0])
            for gi, g in enumerate(GROUNDS[1:], 1):
                reg.assign(np.nonzero(ground == gi), reg.add_model(models[g], name=g))
            # (a) preparation from scratch: tables of every model, EnergyCost, lattice graph; a search
            t0 = time.perf_counter()
            lem = LearnedEnergyModel(reg, robot, ground_preset("asphalt"))
            cost = lem.energy_cost(tmap, SPEED_MPS)
            lat = Lattice.for_cost(cost, stride)
            base["prep_s"].append(time.perf_counter() - t0)
            labels = cost.components()
            main = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
            start = _free_point(cost, (0.05, 0.3), labels, main)
            goal = _free_point(cost, (0.95, 0.7), labels, main)
            t0 = time.perf_counter()
            first = lat.shortest_path(start, goal)
            base["scratch_search_s"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            planner = IncrementalPlanner(lat, goal, heading=False)  # the incremental search: heading-free
            planner.plan(start)
            base["incremental_first_s"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            heading_shortest_path(lat, start, goal)
            base["heading_scratch_s"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            hplanner = IncrementalPlanner(lat, goal)  # the heading lattice's replanner (drive and turns)
            hplanner.plan(start)
            base["heading_first_s"].append(time.perf_counter() - t0)
            for sc in SCENARIOS:
                # (b) one model changes: on a patch across the route, or on every cell of one class
                if sc == "patch":
                    scope = _patch(cost, first.waypoints_m, patch_cells)
                    mid = reg.add_model(updated["asphalt"], name=f"patch{rep}")
                else:
                    scope = ground == GROUNDS.index(changed_ground)
                    mid = reg.add_model(updated[changed_ground], name=f"{changed_ground}-update{rep}")
                reg.assign(np.nonzero(scope), mid)
                t0 = time.perf_counter()
                cost2 = lem.energy_cost(tmap, SPEED_MPS, previous=cost)
                refresh = time.perf_counter() - t0
                lat2 = Lattice.for_cost(cost2, stride)
                # (c) incremental: mark the changed moves' nodes, repair the search
                t0 = time.perf_counter()
                planner.update(lat2)
                update = time.perf_counter() - t0
                t0 = time.perf_counter()
                path = planner.plan(start)
                repair = time.perf_counter() - t0
                # the same replan from scratch on the refreshed lattice, and with refinement
                t0 = time.perf_counter()
                ref = lat2.shortest_path(start, goal)
                search = time.perf_counter() - t0
                # the heading lattice: the replanner's update + search, and a search from scratch
                t0 = time.perf_counter()
                hplanner.update(lat2)
                h_update = time.perf_counter() - t0
                t0 = time.perf_counter()
                hpath = hplanner.plan(start)
                h_repair = time.perf_counter() - t0
                t0 = time.perf_counter()
                href = heading_shortest_path(lat2, start, goal)
                h_search = time.perf_counter() - t0
                t0 = time.perf_counter()
                route = plan_route(tmap, start, goal, cost=cost2, planner="lattice", compare=False,
                                   settings=PlannerSettings(lattice_stride_cells=stride))
                plan_route_s = time.perf_counter() - t0
                rec = per[sc]
                for key, value in (("refresh_s", refresh), ("reweight_s", lat2.build_time_s), ("update_s", update),
                                   ("repair_s", repair), ("search_s", search), ("plan_route_s", plan_route_s),
                                   ("heading_update_s", h_update), ("heading_repair_s", h_repair),
                                   ("heading_search_s", h_search)):
                    rec.setdefault(key, []).append(value)
                if rep == 0:
                    rel = abs(path.objective - ref.objective) / ref.objective if ref.found else float("nan")
                    rec["facts"] = {
                        "changed_cells": int(cost2.changed_cells.sum()),
                        "moves_changed": int(lat2.changed_moves.size),
                        "edges_recomputed": int(lat2.edges_computed),
                        "edges_total": int(lat.n_edges),
                        "nodes_touched": int(planner.touched),
                        "nodes_expanded_repair": int(planner.expanded),
                        "energy_j": float(path.objective),
                        "energy_rel_diff_vs_scratch": rel,
                        "same_found": bool(path.found == ref.found),
                        "route_found": bool(route.found),
                        "heading_states_touched": int(hplanner.expanded),
                        "heading_energy_rel_diff_vs_scratch": (abs(hpath.objective - href.objective) / href.objective
                                                               if href.found else float("nan")),
                    }
                    if sc == SCENARIOS[-1]:  # exactness of the refreshed weights (not timed)
                        fresh = Lattice(LearnedEnergyModel(reg, robot, ground_preset("asphalt")).energy_cost(
                            tmap, SPEED_MPS), stride)
                        g_fresh, g_new = fresh.graph("energy"), lat2.graph("energy")
                        rec["facts"]["weights_equal_fresh_build"] = bool(
                            np.array_equal(g_fresh.data, g_new.data) and np.array_equal(g_fresh.indices, g_new.indices)
                            and np.array_equal(g_fresh.indptr, g_new.indptr))
                cost, lat = cost2, lat2
        b = {k: statistics.median(v) for k, v in base.items()}
        for sc in SCENARIOS:
            m = {k: statistics.median(v) for k, v in per[sc].items() if k != "facts"}
            incremental = m["refresh_s"] + m["update_s"] + m["repair_s"]
            rows_out.append({
                "stride_cells": stride,
                "update": sc,
                **b,
                **m,
                "incremental_s": incremental,
                "full_replan_s": m["refresh_s"] + m["search_s"],
                "refresh_plus_plan_route_s": m["refresh_s"] + m["plan_route_s"],
                "speedup_vs_scratch": (b["prep_s"] + b["scratch_search_s"]) / incremental,
                "speedup_vs_full_replan": (m["refresh_s"] + m["search_s"]) / incremental,
                "repair_speedup_vs_search": m["search_s"] / (m["update_s"] + m["repair_s"]),
                "heading_incremental_s": m["refresh_s"] + m["heading_update_s"] + m["heading_repair_s"],
                "heading_speedup_vs_scratch": (b["prep_s"] + b["heading_scratch_s"])
                / (m["refresh_s"] + m["heading_update_s"] + m["heading_repair_s"]),
                "heading_speedup_vs_full_replan": (m["refresh_s"] + m["heading_search_s"])
                / (m["refresh_s"] + m["heading_update_s"] + m["heading_repair_s"]),
                "heading_repair_speedup_vs_search": m["heading_search_s"] / (m["heading_update_s"] + m["heading_repair_s"]),
                **per[sc]["facts"],
            })
    return {
        "benchmark": "replan",
        "map_cells": [size, size],
        "seed": seed,
        "repeats": repeats,
        "changed_ground": changed_ground,
        "patch_cells": patch_cells,
        "models": len(GROUNDS),
        "numba_warm_up_s": compile_s,
        "load_average_before": list(load_before),
        "load_average_after": list(os.getloadavg()),
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count(), "platform": platform.platform()},
        "target_incremental_s": 0.05,
        "target_speedup_vs_scratch": 10.0,
        "results": rows_out,
    }


def _print(res: dict[str, Any]) -> None:
    print(f"replan benchmark: {res['map_cells'][0]}^2 cells, {res['models']} models; updates: a "
          f"{res['patch_cells']}x{res['patch_cells']} patch on the route, then the '{res['changed_ground']}' class; "
          f"median of {res['repeats']}; load average {res['load_average_before'][0]:.2f} before, "
          f"{res['load_average_after'][0]:.2f} after ({res['machine']['cpus']} cpus)")
    cols = ("stride_cells", "update", "changed_cells", "moves_changed", "prep_s", "scratch_search_s", "refresh_s",
            "reweight_s", "update_s", "repair_s", "search_s", "incremental_s", "speedup_vs_scratch",
            "speedup_vs_full_replan", "nodes_expanded_repair", "energy_rel_diff_vs_scratch",
            "weights_equal_fresh_build")
    print(" ".join(f"{c[:12]:>12s}" for c in cols))
    for r in res["results"]:
        cells = []
        for c in cols:
            v = r.get(c, "")
            cells.append(f"{v:>12.3g}" if c == "energy_rel_diff_vs_scratch" else
                         f"{v:>12.4f}" if isinstance(v, float) else f"{v!s:>12}")
        print(" ".join(cells))
    print("\nheading lattice (drive and turns): the replanner's update + search against a search from scratch")
    hcols = ("stride_cells", "update", "heading_first_s", "heading_scratch_s", "heading_update_s", "heading_repair_s",
             "heading_search_s", "heading_incremental_s", "heading_speedup_vs_scratch",
             "heading_speedup_vs_full_replan", "heading_repair_speedup_vs_search", "heading_states_touched",
             "heading_energy_rel_diff_vs_scratch")
    print(" ".join(f"{c.replace('heading_', '')[:12]:>12s}" for c in hcols))
    for r in res["results"]:
        print(" ".join(f"{r[c]:>12.3g}" if c.endswith("rel_diff_vs_scratch") else f"{r[c]:>12.4f}"
                       if isinstance(r[c], float) else f"{r[c]!s:>12}" for c in hcols))


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="map side in cells (default 512)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--strides", type=int, nargs="+", default=[1, 2], help="lattice strides (cells)")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--patch-cells", type=int, default=20, help="side of the patch update (cells)")
    parser.add_argument("--out", type=Path, default=None, help="write the results as JSON here")
    args = parser.parse_args(argv)
    res = run(args.size, args.repeats, tuple(args.strides), args.seed, args.patch_cells)
    _print(res)
    if args.out is not None:
        write_json_atomic(args.out, res, indent=1)
    return res


if __name__ == "__main__":
    main()
