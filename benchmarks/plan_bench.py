"""Planning benchmark: map preparation, edge-cost throughput, planners vs the lattice optimum.

On seeded procedural maps (1 m cells) of 256^2, 512^2 and 1024^2 cells, for each planner and
each time budget, the script plans a few fixed start/goal queries (crossing the map at
different angles to the lattice directions) and reports

- map preparation: building the :class:`EnergyCost` tables and the 16-connected lattice graph
  (numba compilation is excluded and reported on its own);
- edge-cost throughput: segments per second, in bulk (the lattice path) and one compiled call
  at a time from Python (the OMPL callback path);
- serial vs parallel kernels: segment batches and lattice graphs of several sizes, and lattice
  plans on the bundled example map, timed with the serial kernel, the parallel kernel and the
  variant the library picks by work size (``planner.kernels.PARALLEL_MIN_WALKS``), with their
  ratios in the same run;
- per planner and budget: planning time, route energy (J, turns included), drive energy and
  its ratio to the directed 16-connected 1-cell lattice optimum, energy saved against the
  shortest-distance route. The lattice optimum minimises drive energy alone while the
  library's planners minimise drive + turn energy (they trade a little drive energy for
  fewer turns), so every refined planner also runs on the lattice's own objective (turn
  table zeroed, ``[drive obj]``); each route is scored on the true cost, turns included,
  and each target is checked on the objective the route minimised;
- the heading lattice (:mod:`planner.heading_lattice`, the search that pays for its turns)
  beside the heading-free A* on the same 1-cell lattice: median query times and their ratio,
  the heading query's added peak memory (forked child, VmHWM) and each answer's price;
- the any-angle planner (``planner="anyangle"``: Theta* in a corridor around a coarse lattice
  route, then its compiled polish) as a quality-versus-time curve on the lattice's objective:
  several settings (guide stride, corridor width, raw or polished), each planned
  ``--repeats`` times (median time; the planner is deterministic), and the stages of one
  default run (guide route, Theta*, each polishing pass); times and ratios are also given
  as ratios to the lattice + refinement on the same objective in the same run.

All ratios are against baselines computed in the same run on the same machine; absolute times
depend on the machine (the project's targets are stated for a 2-core machine). Usage::

    python benchmarks/plan_bench.py --out bench_plan.json          # full run (several minutes)
    python benchmarks/plan_bench.py --quick                         # small run (~1 minute)
    python benchmarks/plan_bench.py --sizes 512 --budgets 0.1 0.25 0.5 --planners RRTstar BITstar \
        --refine --no-parallel-table --out plan.json                # the any-angle target (~2 minutes)
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from energy import PhysicsEnergyModel, ground_preset, robot_preset
from planner import CostSpec, CostTables, EnergyCost, Lattice, PlannerSettings, plan_route, warm_up_kernels
from planner.anyangle import DEFAULT_POLISH_SPACINGS_CELLS, anyangle_path, polish_path, warm_up_anyangle
from planner.kernels import variants
from planner.ompl import OMPL_PLANNERS
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map, procedural_map
from terrawatt_base.atomic import write_json_atomic

# Start/goal as fractions of the map extent: about 12, 45 and 74 degrees from the x axis.
QUERIES = (((0.05, 0.30), (0.95, 0.50)), ((0.08, 0.06), (0.92, 0.94)), ((0.30, 0.05), (0.55, 0.95)))
# FMT* is a batch planner (its work is its sample count): per query, two probes (100 and 300
# samples) fit its time as a power of the sample count, and each budget then gets the sample
# count expected to fill ``FMT_FILL`` of it; the time limit is 1.5 x the budget, the actual
# planning time is reported.
FMT_PROBES = (100, 300)
FMT_FILL = 0.5
# Any-angle settings of the quality-versus-time curve: (label, guide stride, corridor cells, polished).
ANYANGLE_SETTINGS = (
    ("guide 4, corridor 6, raw", 4, 6, False),
    ("guide 2, corridor 12, raw", 2, 12, False),
    ("guide 4, corridor 6 + polish", 4, 6, True),
    ("guide 2, corridor 12 + polish (default)", 2, 12, True),
    ("guide 1, corridor 12 + polish", 1, 12, True),
    ("guide 1, corridor 24 + polish", 1, 24, True),
)
#: Piece lengths (cells) of the long polish, the last point of the any-angle curve.
LONG_POLISH_SPACINGS_CELLS = (8.0, 4.0, 2.0, 1.0)
#: The any-angle target on 512^2 maps (lattice objective): median ratio and the slowest query.
ANYANGLE_TARGET_RATIO = 0.983
ANYANGLE_TARGET_S = 0.15


def _free_point(
    cost: EnergyCost, frac: tuple[float, float], labels: np.ndarray, want: int | None
) -> tuple[float, float]:
    """The free cell centre nearest to a fractional map position (in component ``want`` if given)."""
    rows, cols = cost.shape
    r0, c0 = int(frac[1] * (rows - 1)), int(frac[0] * (cols - 1))
    ok = (~cost.blocked) & ((labels == want) if want is not None else (labels > 0))
    rr, cc = np.nonzero(ok)
    k = int(np.argmin((rr - r0) ** 2 + (cc - c0) ** 2))
    x, y = cost.terrain.xy(rr[k], cc[k])
    return (float(x), float(y))


def _queries(cost: EnergyCost, n_queries: int) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    labels = cost.components()
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    main = int(np.argmax(sizes))  # plan inside the largest free region
    return [(_free_point(cost, a, labels, main), _free_point(cost, b, labels, main)) for a, b in QUERIES[:n_queries]]


def _edge_rates(cost: EnergyCost, rng: np.random.Generator) -> dict[str, float]:
    xmin, ymin, xmax, ymax = cost.terrain.bounds
    n = 200_000
    a = rng.uniform([xmin, ymin], [xmax, ymax], size=(n, 2))
    step = rng.normal(0, 5.0 * cost.terrain.cell_size_m, size=(n, 2))
    b = np.clip(a + step, [xmin, ymin], [xmax, ymax])
    cost.segment_energy_j(a[:1000], b[:1000])
    t0 = time.perf_counter()
    cost.segment_energy_j(a, b)
    bulk = n / (time.perf_counter() - t0)
    m = 50_000
    one = cost.segment_energy_one_j
    t0 = time.perf_counter()
    for i in range(m):
        one(a[i, 0], a[i, 1], b[i, 0], b[i, 1])
    single = m / (time.perf_counter() - t0)
    mean_len = float(np.mean(np.hypot(*(b - a).T)))
    return {"bulk_segments_per_s": bulk, "single_call_segments_per_s": single, "mean_segment_m": mean_len}


def _warm_up_planners() -> float:
    """One tiny plan per planner so first-call costs (imports, dispatch) are not timed."""
    t0 = time.perf_counter()
    tmap = procedural_map((48, 48), 1.0, seed=1, n_ridges=0, obstacle_fraction=0.0)
    cost = _make_cost(tmap, "husky")
    for planner in (*OMPL_PLANNERS, "anyangle", "lattice"):
        plan_route(tmap, (3.5, 3.5), (44.5, 40.5), cost=cost, planner=planner, time_limit_s=0.05, seed=0,
                   settings=PlannerSettings(fmt_samples=50))
    return time.perf_counter() - t0


def _make_cost(tmap, robot: str) -> EnergyCost:
    model = PhysicsEnergyModel(robot_preset(robot))
    grounds = {name: ground_preset(name) for name in tmap.ground_names.values()}
    return CostSpec(energy_model=model, grounds=grounds, speed_mps=0.5).build(tmap)


def _best_time(fn: Any, repeats: int) -> float:
    """Median wall time (s) of ``repeats`` calls of ``fn``."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _with_threshold(threshold: int, fn: Any) -> Any:
    """Run ``fn`` with ``planner.kernels.variants.PARALLEL_MIN_WALKS`` set to ``threshold``."""
    saved = variants.PARALLEL_MIN_WALKS
    variants.PARALLEL_MIN_WALKS = threshold
    try:
        return fn()
    finally:
        variants.PARALLEL_MIN_WALKS = saved


def _variant_times(fn: Any, repeats: int) -> dict[str, float]:
    """Median times of ``fn`` forced serial, forced parallel and as chosen by work size."""
    out = {}
    for label, threshold in (("serial", 2**62), ("parallel", 0), ("chosen", variants.PARALLEL_MIN_WALKS)):
        out[f"{label}_s"] = _with_threshold(threshold, lambda: _best_time(fn, repeats))
    out["parallel_over_serial"] = out["parallel_s"] / out["serial_s"]
    out["chosen_over_best"] = out["chosen_s"] / min(out["serial_s"], out["parallel_s"])
    return out


def _parallel_table(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Serial vs parallel vs chosen: segment batches, lattice graphs, lattice plans on the example map."""
    import numba

    rows: list[dict[str, Any]] = []
    side = 128 if args.quick else 256
    tmap = procedural_map((side, side), 1.0, seed=args.seed)
    cost = _make_cost(tmap, args.robot)
    rng = np.random.default_rng(args.seed)
    for n in (10, 100, 1_000, 10_000, 100_000):
        a = rng.uniform(0.0, side, size=(n, 2))
        b = np.clip(a + rng.normal(0.0, 5.0, size=(n, 2)), 0.0, side)
        repeats = max(3, min(200, 200_000 // n))
        rows.append({"work": "segment_energy_j", "size": f"{n} segments", "walks": n,
                     **_variant_times(lambda a=a, b=b: cost.segment_energy_j(a, b), repeats)})
    for n in ((32, 64) if args.quick else (32, 64, 128, 256)):
        sub = procedural_map((n, n), 1.0, seed=args.seed)
        sub_cost = _make_cost(sub, args.robot)
        rows.append({"work": "Lattice graph", "size": f"{n}^2 cells", "walks": n * n * 8,
                     **_variant_times(lambda c=sub_cost: Lattice(c, 1), 3)})
    bundled = example_map()
    bundled_cost = _make_cost(bundled, args.robot)
    Lattice.for_cost(bundled_cost, 1)  # map preparation, not timed

    def lattice_plan() -> None:
        plan_route(bundled, EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M, cost=bundled_cost, planner="lattice")

    rows.append({"work": "plan_route lattice", "size": f"example map {bundled.shape[0]}x{bundled.shape[1]}",
                 "walks": None, **_variant_times(lattice_plan, 3 if args.quick else 5)})
    for r in rows:
        r["numba_threads"] = numba.get_num_threads()
        r["threshold_walks"] = variants.PARALLEL_MIN_WALKS
    return rows


def _peak_rss_delta_bytes(fn: Any) -> int:
    """Peak resident memory ``fn`` adds (bytes), measured in a forked child (its high-water mark minus
    its resident size before the call); -1 where /proc is not there."""
    import multiprocessing

    def child(conn: Any) -> None:
        def rss(key: str) -> int:
            for line in Path("/proc/self/status").read_text().splitlines():
                if line.startswith(key):
                    return int(line.split()[1]) * 1024
            return -1

        before = rss("VmRSS:")
        fn()
        conn.send(rss("VmHWM:") - before)
        conn.close()

    if not Path("/proc/self/status").exists():
        return -1
    ctx = multiprocessing.get_context("fork")
    parent, child_conn = ctx.Pipe()
    proc = ctx.Process(target=child, args=(child_conn,))
    proc.start()
    value = parent.recv()
    proc.join()
    return int(value)


def _heading_table(args: argparse.Namespace) -> list[dict[str, Any]]:
    """The heading lattice (drive + turns over node x 16 headings) beside the heading-free A* on the same lattice:
    median query times and their ratio, the heading query's added peak memory, and the price of each answer."""
    from planner.heading_lattice import heading_shortest_path

    rows = []
    for n in args.sizes:
        tmap = procedural_map((n, n), 1.0, seed=args.seed)
        cost = _make_cost(tmap, args.robot)
        lattice = Lattice.for_cost(cost, 1)
        for k, (start, goal) in enumerate(_queries(cost, args.queries)):
            free = lattice.shortest_path(start, goal)
            heading = heading_shortest_path(lattice, start, goal)
            t_free = _best_time(lambda s=start, g=goal, lat=lattice: lat.shortest_path(s, g), args.repeats)
            t_head = _best_time(lambda s=start, g=goal, lat=lattice: heading_shortest_path(lat, s, g), args.repeats)
            peak = _peak_rss_delta_bytes(lambda s=start, g=goal, lat=lattice: heading_shortest_path(lat, s, g))
            rows.append({
                "cells": f"{n}^2", "query": k, "heading_free_s": t_free, "heading_s": t_head,
                "ratio": t_head / t_free, "heading_peak_added_mib": peak / 2**20 if peak >= 0 else None,
                "heading_free_drive_j": free.objective, "heading_free_priced_j": cost.path_energy_j(free.waypoints_m),
                "heading_j": heading.objective,
            })
    return rows


def _print_heading(rows: list[dict[str, Any]]) -> None:
    print("\nheading lattice (node x 16 headings, drive + turns) beside the heading-free A* (median seconds; energies "
          "in J: the heading-free route's drive objective, its price with turns, the heading lattice's optimum)")
    print(f"{'cells':<8} {'query':>5} {'free s':>8} {'heading s':>10} {'ratio':>6} {'peak MiB':>9} {'free drive':>11} "
          f"{'free priced':>12} {'heading':>10}")
    for r in rows:
        peak = "n/a" if r["heading_peak_added_mib"] is None else f"{r['heading_peak_added_mib']:.0f}"
        print(f"{r['cells']:<8} {r['query']:5d} {r['heading_free_s']:8.3f} {r['heading_s']:10.3f} {r['ratio']:6.2f} "
              f"{peak:>9} {r['heading_free_drive_j']:11.0f} {r['heading_free_priced_j']:12.0f} {r['heading_j']:10.0f}")


def _print_parallel(rows: list[dict[str, Any]]) -> None:
    print(f"\nserial vs parallel kernels (numba threads {rows[0]['numba_threads']}, parallel from "
          f"{rows[0]['threshold_walks']} walks; median seconds)")
    print(f"{'work':<20} {'size':<26} {'serial s':>9} {'parallel s':>11} {'chosen s':>9} {'par/ser':>8} {'chosen/best':>12}")
    for r in rows:
        print(f"{r['work']:<20} {r['size']:<26} {r['serial_s']:9.5f} {r['parallel_s']:11.5f} {r['chosen_s']:9.5f} "
              f"{r['parallel_over_serial']:8.2f} {r['chosen_over_best']:12.2f}")


def _run_size(n: int, args: argparse.Namespace, rng: np.random.Generator) -> dict[str, Any]:
    tmap = procedural_map((n, n), 1.0, seed=args.seed)
    cost = _make_cost(tmap, args.robot)
    t0 = time.perf_counter()
    lattice = Lattice.for_cost(cost, 1)
    lattice_build_s = time.perf_counter() - t0
    guide_stride = PlannerSettings().anyangle_guide_stride_cells
    t0 = time.perf_counter()
    Lattice.for_cost(cost, guide_stride)  # the any-angle planner's guide graph (carried to drive_cost)
    guide_build_s = time.perf_counter() - t0
    prep = {
        "cells": n * n,
        "cost_tables_s": cost.prep_time_s,
        "lattice_graph_s": lattice_build_s,
        "map_preparation_s": cost.prep_time_s + lattice_build_s,
        "anyangle_guide_graph_s": guide_build_s,
        "anyangle_guide_stride_cells": guide_stride,
        "lattice_edges": lattice.n_edges,
        "blocked_fraction": float(cost.blocked.mean()),
    }
    prep.update(_edge_rates(cost, rng))
    queries = _queries(cost, args.queries)
    drive_cost = cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, np.zeros_like(cost.tables.turn_table_j)))
    runs: list[dict[str, Any]] = []
    curve: list[dict[str, Any]] = []
    for qi, (start, goal) in enumerate(queries):
        t0 = time.perf_counter()
        optimum = lattice.shortest_path(start, goal)
        optimum_s = time.perf_counter() - t0
        optimum_total_j = cost.path_energy_j(optimum.waypoints_m)
        base = {"size": n, "query": qi, "start_xy_m": start, "goal_xy_m": goal, "lattice_optimum_j": optimum.objective,
                "lattice_optimum_total_j": optimum_total_j}
        runs.append({**base, "planner": "lattice-optimum", "budget_s": None, "status": "exact",
                     "planning_time_s": optimum_s, "drive_energy_j": optimum.objective,
                     "energy_j": optimum_total_j, "ratio": 1.0, "total_ratio": 1.0, "energy_saved_pct": math.nan})
        fmt_fit = None
        if "FMT" in args.planners:
            times = []
            for samples in FMT_PROBES:
                probe = plan_route(tmap, start, goal, cost=cost, planner="FMT", time_limit_s=30.0, seed=args.seed,
                                   refine=False, settings=PlannerSettings(fmt_samples=samples))
                times.append(max(probe.planning_time_s, 1e-4))
            power = max(1.0, math.log(times[1] / times[0]) / math.log(FMT_PROBES[1] / FMT_PROBES[0]))
            fmt_fit = (times[0] / FMT_PROBES[0] ** power, power)  # t(n) = a n^p
        # (planner, budget, refine, objective): "turns" is the library's objective (drive +
        # turn energy); "drive" plans with the turn table zeroed, the lattice's own objective.
        variants: list[tuple[str, float | None, bool, str]] = [
            ("lattice", None, True, "turns"), ("lattice", None, True, "drive"),
            ("anyangle", None, False, "drive"), ("anyangle", None, True, "turns"), ("anyangle", None, True, "drive"),
        ]
        for planner in args.planners:
            for budget in args.budgets:
                variants.append((planner, budget, False, "turns"))
                if args.refine:
                    variants.append((planner, budget, True, "turns"))
                    variants.append((planner, budget, True, "drive"))
        for planner, budget, refine, objective in variants:
            settings = PlannerSettings()
            limit = budget
            if planner == "FMT" and budget is not None:
                a, power = fmt_fit
                samples = int(np.clip((FMT_FILL * budget / a) ** (1.0 / power), 50, 50_000))
                settings = PlannerSettings(fmt_samples=samples)
                limit = 1.5 * budget
            route = plan_route(
                tmap, start, goal, cost=drive_cost if objective == "drive" else cost, planner=planner,
                time_limit_s=limit if limit else 1.0, seed=args.seed, refine=refine, settings=settings,
                compare=True,
            )
            # every route is scored on the true cost (turns included), whatever it optimised
            energy_j = cost.path_energy_j(route.waypoints_m) if route.found else math.nan
            runs.append({
                **base,
                "planner": planner + ("+refine" if refine else "") + (" [drive obj]" if objective == "drive" else ""),
                "objective": objective,
                "budget_s": budget,
                "status": route.status,
                "planning_time_s": route.planning_time_s,
                "drive_energy_j": route.drive_energy_j,
                "energy_j": energy_j,
                "ratio": route.optimality_ratio,
                "total_ratio": energy_j / optimum_total_j,
                "energy_saved_pct": route.energy_saved_pct,
                "n_waypoints": int(route.waypoints_m.shape[0]),
                "fmt_samples": settings.fmt_samples if planner == "FMT" else None,
            })
            _progress(f"  {n}^2 q{qi} {runs[-1]['planner']:<22} budget {budget!s:>4}: {route.status:<11} "
                      f"{route.planning_time_s:6.3f} s  ratio {route.optimality_ratio:.4f}")
        curve.extend({**base, **row} for row in _anyangle_curve(tmap, drive_cost, start, goal, optimum.objective, args))
    return {"size": n, "preparation": prep, "runs": runs, "anyangle_curve": curve}


def _anyangle_curve(tmap, drive_cost: EnergyCost, start, goal, optimum_j: float,
                    args: argparse.Namespace) -> list[dict[str, Any]]:
    """Quality versus time of the any-angle planner on one query, on the lattice's objective.

    One row per setting of :data:`ANYANGLE_SETTINGS` (``plan_route``, median time of
    ``args.repeats`` runs) and one per stage of a default run (guide lattice route, Theta*,
    each polishing pass; cumulative times), plus the lattice + refinement on the same
    objective, run as often, as the reference of the time and ratio ratios.
    """
    rows: list[dict[str, Any]] = []

    def timed(fn: Any) -> tuple[Any, float]:
        times, out = [], None
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        return out, statistics.median(times)

    def lattice_refined() -> Any:
        return plan_route(tmap, start, goal, cost=drive_cost, planner="lattice", seed=args.seed)

    routes = [lattice_refined() for _ in range(args.repeats)]
    ref_s = statistics.median(r.planning_time_s for r in routes)
    ref_ratio = routes[0].drive_energy_j / optimum_j
    rows.append({"planner": "curve: lattice+refine [drive obj]", "curve": "reference", "setting": "lattice+refine",
                 "planning_time_s": ref_s, "ratio": ref_ratio, "time_over_lattice_refine": 1.0,
                 "ratio_over_lattice_refine": 1.0})
    for label, stride, width, polished in ANYANGLE_SETTINGS:
        settings = PlannerSettings(anyangle_guide_stride_cells=stride, anyangle_corridor_cells=width)
        Lattice.for_cost(drive_cost, stride)  # map preparation, not timed
        routes = [plan_route(tmap, start, goal, cost=drive_cost, planner="anyangle", refine=polished,
                             settings=settings) for _ in range(args.repeats)]
        t = statistics.median(r.planning_time_s for r in routes)
        ratio = routes[0].drive_energy_j / optimum_j
        rows.append({"planner": f"curve: anyangle {label}", "curve": "settings", "setting": label,
                     "planning_time_s": t, "ratio": ratio, "time_over_lattice_refine": t / ref_s,
                     "ratio_over_lattice_refine": ratio / ref_ratio})
    # the stages of one default run
    default = PlannerSettings()
    guide_lattice = Lattice.for_cost(drive_cost, default.anyangle_guide_stride_cells)
    guide, t_guide = timed(lambda: guide_lattice.shortest_path(start, goal))
    path, t_any = timed(lambda: anyangle_path(drive_cost, start, goal,
                                              guide_stride_cells=default.anyangle_guide_stride_cells,
                                              corridor_cells=default.anyangle_corridor_cells))
    stages = [("guide lattice route", t_guide, drive_cost.path_energy_j(guide.waypoints_m)),
              ("+ Theta* in the corridor", t_any, path.drive_energy_j)]
    wp, total = path.waypoints_m, t_any
    cell = drive_cost.terrain.cell_size_m
    for spacing in DEFAULT_POLISH_SPACINGS_CELLS:
        wp, t_pass = timed(lambda wp=wp, spacing=spacing: polish_path(drive_cost, wp, spacings_m=(spacing * cell,)))
        total += t_pass
        stages.append((f"+ polish, {spacing:g}-cell pieces", total, drive_cost.path_energy_j(wp)))
    # more time: a long polish of the Theta* route (where the route's local optimum lies)
    long_m = tuple(c * cell for c in LONG_POLISH_SPACINGS_CELLS)
    wp, t_long = timed(lambda: polish_path(drive_cost, path.waypoints_m, spacings_m=long_m, step_min_m=0.01 * cell,
                                           max_sweeps=1000))
    stages.append(("+ long polish instead (8, 4, 2, 1 cells, 1 % steps)", t_any + t_long,
                   drive_cost.path_energy_j(wp)))
    for label, t, energy in stages:
        rows.append({"planner": f"stage: {label}", "curve": "stages", "setting": label, "planning_time_s": t,
                     "ratio": energy / optimum_j, "time_over_lattice_refine": t / ref_s,
                     "ratio_over_lattice_refine": energy / optimum_j / ref_ratio})
    for r in rows:
        _progress(f"    {r['planner']:<52} {r['planning_time_s']:6.3f} s  ratio {r['ratio']:.4f}")
    return rows


def _summarise_curve(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Medians over queries of each point of the any-angle curve."""
    rows = []
    for res in results:
        groups: dict[str, list[dict[str, Any]]] = {}
        for run in res["anyangle_curve"]:
            groups.setdefault(run["planner"], []).append(run)
        for planner, runs in groups.items():
            rows.append({
                "size": res["size"],
                "planner": planner,
                "curve": runs[0]["curve"],
                "n": len(runs),
                "planning_time_s_median": statistics.median(r["planning_time_s"] for r in runs),
                "planning_time_s_max": max(r["planning_time_s"] for r in runs),
                "ratio_median": statistics.median(r["ratio"] for r in runs),
                "ratio_max": max(r["ratio"] for r in runs),
                "time_over_lattice_refine_median": statistics.median(r["time_over_lattice_refine"] for r in runs),
                "ratio_over_lattice_refine_median": statistics.median(r["ratio_over_lattice_refine"] for r in runs),
            })
    return rows


def _print_curve(rows: list[dict[str, Any]]) -> None:
    print("\nany-angle quality vs time, lattice's objective (medians over queries; ratio = drive energy / lattice")
    print("optimum; '/ lat+ref' = the any-angle value over the lattice + refinement's on the same query, same run)")
    print(f"{'size':>6} {'point':<56} {'plan s':>7} {'max s':>6} {'ratio':>7} {'max':>7} "
          f"{'s / lat+ref':>12} {'ratio / lat+ref':>16}")
    for r in rows:
        print(f"{r['size']:>5}² {r['planner']:<56} {r['planning_time_s_median']:7.3f} {r['planning_time_s_max']:6.3f} "
              f"{r['ratio_median']:7.4f} {r['ratio_max']:7.4f} {r['time_over_lattice_refine_median']:12.3f} "
              f"{r['ratio_over_lattice_refine_median']:16.4f}")


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _summarise(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for res in results:
        groups: dict[tuple[str, Any], list[dict[str, Any]]] = {}
        for run in res["runs"]:
            groups.setdefault((run["planner"], run["budget_s"]), []).append(run)
        for (planner, budget), runs in groups.items():
            ratios = [r["ratio"] for r in runs if math.isfinite(r["ratio"])]
            totals = [r["total_ratio"] for r in runs if math.isfinite(r["total_ratio"])]
            objective = runs[0].get("objective", "turns")
            saved = [r["energy_saved_pct"] for r in runs if math.isfinite(r["energy_saved_pct"])]
            energies = [r["energy_j"] for r in runs if math.isfinite(r["energy_j"])]
            rows.append({
                "size": res["size"],
                "planner": planner,
                "budget_s": budget,
                "n": len(runs),
                "exact": sum(r["status"] == "exact" for r in runs),
                "planning_time_s_median": statistics.median(r["planning_time_s"] for r in runs),
                "planning_time_s_max": max(r["planning_time_s"] for r in runs),
                "ratio_median": statistics.median(ratios) if ratios else math.nan,
                "ratio_max": max(ratios) if ratios else math.nan,
                "objective": objective,
                "total_ratio_median": statistics.median(totals) if totals else math.nan,
                "total_ratio_max": max(totals) if totals else math.nan,
                "energy_j_mean": statistics.fmean(energies) if energies else math.nan,
                "energy_saved_pct_median": statistics.median(saved) if saved else math.nan,
            })
    return rows


def _print_tables(results: list[dict[str, Any]], rows: list[dict[str, Any]], compile_s: float) -> None:
    print(f"numba kernels compile/load: {compile_s:.2f} s (not part of map preparation)")
    print("\nmap preparation and edge-cost throughput")
    print(f"{'size':>6} {'tables s':>9} {'lattice s':>10} {'prep s':>7} {'guide s':>8} {'edges':>10} "
          f"{'bulk seg/s':>12} {'1-call seg/s':>13} {'blocked':>8}")
    for res in results:
        p = res["preparation"]
        print(f"{res['size']:>5}² {p['cost_tables_s']:9.3f} {p['lattice_graph_s']:10.3f} "
              f"{p['map_preparation_s']:7.3f} {p['anyangle_guide_graph_s']:8.3f} "
              f"{p['lattice_edges']:10d} {p['bulk_segments_per_s']:12.3g} {p['single_call_segments_per_s']:13.3g} "
              f"{p['blocked_fraction']:8.3f}")
    print("\nplanners (medians over queries; ratio = drive energy / 16-connected 1-cell lattice optimum;")
    print("          E ratio = total energy with turns / that of the lattice-optimum route)")
    print(f"{'size':>6} {'planner':<30} {'budget':>6} {'exact':>6} {'plan s':>7} {'max s':>6} {'ratio':>7} "
          f"{'max':>7} {'E ratio':>8} {'E mean J':>10} {'saved %':>8}")
    for r in rows:
        budget = "-" if r["budget_s"] is None else f"{r['budget_s']:g}"
        print(f"{r['size']:>5}² {r['planner']:<30} {budget:>6} {r['exact']:>3}/{r['n']:<2} "
              f"{r['planning_time_s_median']:7.3f} {r['planning_time_s_max']:6.3f} {r['ratio_median']:7.4f} "
              f"{r['ratio_max']:7.4f} {r['total_ratio_median']:8.4f} "
              f"{r['energy_j_mean']:10.0f} "
              f"{r['energy_saved_pct_median']:8.2f}")


def _targets(results: list[dict[str, Any]], rows: list[dict[str, Any]],
             curve_rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The project's 512^2 targets, checked against this run."""
    out = []
    for r in curve_rows:
        if r["size"] == 512 and r["curve"] == "settings":
            good = r["ratio_median"] <= ANYANGLE_TARGET_RATIO
            fast = r["planning_time_s_max"] <= ANYANGLE_TARGET_S
            out.append({
                "target": f"512^2 {r['planner']} median ratio <= {ANYANGLE_TARGET_RATIO} within {ANYANGLE_TARGET_S} s",
                "value": {k: r[k] for k in ("ratio_median", "ratio_max", "planning_time_s_median",
                                            "planning_time_s_max", "time_over_lattice_refine_median")},
                "met": bool(good and fast),
            })
    for res in results:
        if res["size"] != 512:
            continue
        prep = res["preparation"]["map_preparation_s"]
        out.append({"target": "512^2 map preparation <= 1 s", "value": prep, "met": prep <= 1.0})
        for r in rows:
            if r["size"] == 512 and r["planner"] != "lattice-optimum":
                # each route against the lattice optimum on the objective it minimised: drive
                # energy for the drive objective; drive + turns (that of the lattice-optimum
                # route) for the library's turn-aware objective
                key = "ratio" if r["objective"] == "drive" else "total_ratio"
                fast = r["planning_time_s_max"] <= 0.5
                good = r[f"{key}_median"] <= 0.99
                out.append({
                    "target": f"512^2 {r['planner']} (budget {r['budget_s']}) median {key} <= 0.99 within 0.5 s",
                    "value": {f"{key}_median": r[f"{key}_median"], f"{key}_max": r[f"{key}_max"],
                              "planning_time_s_max": r["planning_time_s_max"]},
                    "met": bool(fast and good),
                })
    return out


def _clean(obj: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, tuples -> lists, numpy scalars -> Python."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, (np.integer, np.bool_)):
        return obj.item()
    return obj


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024], help="map sides in cells")
    parser.add_argument("--budgets", type=float, nargs="+", default=[0.5, 1.0, 2.0], help="OMPL time budgets (s)")
    parser.add_argument("--planners", nargs="+", default=["RRTstar", "InformedRRTstar", "BITstar", "FMT"],
                        choices=list(OMPL_PLANNERS), help="OMPL planners (the lattice planner always runs)")
    parser.add_argument("--refine", action="store_true", help="also run each OMPL planner with refinement")
    parser.add_argument("--queries", type=int, default=3, choices=[1, 2, 3], help="start/goal pairs per map")
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of each any-angle curve point (median time; the planner is deterministic)")
    parser.add_argument("--robot", default="husky", help="robot preset")
    parser.add_argument("--seed", type=int, default=0, help="map and planner seed")
    parser.add_argument("--quick", action="store_true", help="small run: 256^2, budgets 0.25/0.5, 2 queries")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    parser.add_argument("--no-parallel-table", dest="parallel_table", action="store_false",
                        help="skip the serial vs parallel kernel table")
    parser.add_argument("--no-heading-table", dest="heading_table", action="store_false",
                        help="skip the heading lattice beside the heading-free A*")
    args = parser.parse_args(argv)
    if args.quick:
        args.sizes, args.budgets, args.queries = [256], [0.25, 0.5], 2
        args.planners = ["RRTstar", "BITstar", "FMT"]
    rng = np.random.default_rng(args.seed)
    compile_s = warm_up_kernels() + warm_up_anyangle()
    warm_s = _warm_up_planners()
    parallel_rows = _parallel_table(args) if args.parallel_table else []
    results = []
    for n in args.sizes:
        _progress(f"map {n}^2 ...")
        results.append(_run_size(n, args, rng))
    rows = _summarise(results)
    curve_rows = _summarise_curve(results)
    _print_tables(results, rows, compile_s)
    _print_curve(curve_rows)
    if parallel_rows:
        _print_parallel(parallel_rows)
    heading_rows = _heading_table(args) if args.heading_table else []
    if heading_rows:
        _print_heading(heading_rows)
    targets = _targets(results, rows, curve_rows)
    if heading_rows:
        at512 = [r for r in heading_rows if r["cells"] == "512^2"]
        if at512:
            worst = max(r["ratio"] for r in at512)
            peaks = [r["heading_peak_added_mib"] for r in at512 if r["heading_peak_added_mib"] is not None]
            targets.append({"target": "512^2 heading-lattice query <= 8x the heading-free A*", "met": worst <= 8.0,
                            "value": f"worst {worst:.2f}x"})
            if peaks:
                targets.append({"target": "512^2 heading-lattice query <= 2 GiB", "met": max(peaks) <= 2048,
                                "value": f"{max(peaks):.0f} MiB added at most"})
    for t in targets:
        print(f"{'MET ' if t['met'] else 'NOT MET'} {t['target']}: {t['value']}")
    if args.out is not None:
        payload = {
            "benchmark": "plan_bench",
            "version": 2,
            "args": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
            "machine": {
                "cpu_count": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version()
            },
            "numba_compile_s": compile_s,
            "planner_warm_up_s": warm_s,
            "sizes": results,
            "summary": rows,
            "anyangle_curve": curve_rows,
            "parallel": parallel_rows,
            "heading": heading_rows,
            "targets": targets,
        }
        write_json_atomic(args.out, _clean(payload), indent=1)
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
