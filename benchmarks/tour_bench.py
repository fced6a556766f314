"""Tour benchmark: 200 sites, 3 robots on one charge each — pair pricing and solving times, PyVRP vs OR-Tools, Monte Carlo.

- **pricing and solving**: on a seeded 512 x 512 procedural map (1 m cells) with a run-level
  spread on every ground (``--rel-sd`` of the mean: the presets give no interval), 200 random
  sites with values 1-5 in the depot's free region and 3 robots sharing one depot:
  :func:`planner.tours.price_pairs` (one lattice search per point, on ``--workers`` dask
  processes) and :func:`planner.tours.plan_tour` given those prices (PyVRP, each tour checked at
  its own quantile) are timed apart; the target is pricing plus solving <= 120 s on 2 cores;
- **PyVRP vs OR-Tools**: the same integer problem solved by both (:mod:`planner.tours.solver`;
  OR-Tools' routing solver with guided local search, its time limit ``--ortools-s``): value and
  seconds;
- **Monte Carlo**: the tours planned at Q = 0.9 and at Q = 0.5 driven ``--mc`` times each through
  :func:`planner.tours.simulate_tours_mc` (the planning model's own distribution: one factor per
  ground per tour): the share of tours ending above the reserve beside Q. On the bundled example
  map with ``--model FILE`` (a saved model with an interval, e.g. ``terrawatt train`` output) its
  interval prices the edges; without it, a small vibration estimator fitted here on simulated runs
  of the map's four grounds (its cross-validated interval; ``--stated-spread``: the presets with
  ``--rel-sd`` instead).
- **charging points**: on the bundled example map with the stated spread, ``--charger-sites`` sites,
  ``--chargers`` charging points in the depot's region and two robots whose charge reaches about one
  median round trip: the value planned without the chargers (PyVRP) and with them (OR-Tools, its
  time limit ``--ortools-s``; each segment between charges checked at its own quantile), the
  seconds, the charging stops, and the Monte Carlo of the tours with charges at Q = 0.9: the share
  above the reserve at every charger arrival and back, and at the worst single arrival.

Needs the ``bench`` (OR-Tools) and ``distributed`` extras. Times are of a shared machine: run it with
``nice``. Usage::

    python benchmarks/tour_bench.py --out bench_tour.json          # 512^2, 200 sites (~2-3 min)
    python benchmarks/tour_bench.py --quick                          # 192^2, 60 sites (~30 s)
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from energy import Battery, TruthSimulator, VibrationCurrentEstimator, ground_preset, load_current_model, robot_preset
from energy.models.config import estimator_preset
from energy.sim import GroundVariation
from planner import CostTables, EnergyCost, warm_up_kernels
from planner.cost_spec import CostSpec
from planner.tours import (
    TourChargers,
    TourPoints,
    TourRobot,
    TourSearch,
    TourSites,
    plan_tour,
    price_pairs,
    simulate_tours_mc,
)
from planner.tours.solver import TourProblem, solve_ortools, solve_pyvrp
from terrain import TerrainMap, example_map
from terrain.procedural import procedural_map
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.dask_client import Compute


def with_spread(cost: EnergyCost, rel_sd: float) -> EnergyCost:
    """``cost`` with a run-level spread of ``rel_sd`` of every mean table entry."""
    sd = np.nan_to_num(np.abs(rel_sd * cost.tables.grade_table_j_per_m), nan=0.0, posinf=0.0)
    return cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j, ground_labels=cost.tables.ground_labels, grade_sd_table_j_per_m=sd, turn_sd_table_j=np.abs(rel_sd * cost.tables.turn_table_j)))


def depot_and_sites(cost: EnergyCost, n: int, rng: np.random.Generator) -> tuple[tuple[float, float], TourSites]:
    """A depot near the map's centre and ``n`` sites, all in the depot's free region, values 1-5."""
    labels, _ = ndimage.label(~np.asarray(cost.blocked))
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    free = np.argwhere(labels == int(np.argmax(sizes)))
    xc, yc = cost.terrain.cell_centres()
    centre = np.array(cost.shape) / 2
    d = free[np.argmin(np.hypot(*(free - centre).T))]
    pick = free[rng.choice(len(free), n, replace=False)]
    sites = TourSites(tuple(f"site{k:03d}" for k in range(n)), np.column_stack([xc[pick[:, 1]], yc[pick[:, 0]]]),
                      value=rng.integers(1, 6, n).astype(float))
    return (float(xc[d[1]]), float(yc[d[0]])), sites


def battery_for(prices: Any, trips: float, voltage_v: float, reserve_pct: float = 20.0) -> Battery:
    """A battery whose budget above the reserve is ``trips`` x the sites' median mean round trip from the depot."""
    round_trip = prices.mean_j[0, 1:] + prices.mean_j[1:, 0]
    budget = trips * float(np.median(round_trip[np.isfinite(round_trip)]))
    return Battery(budget / ((1 - reserve_pct / 100) * voltage_v * 3600.0), voltage_v, min_reserve_pct=reserve_pct)


def timing_part(args: argparse.Namespace) -> dict[str, Any]:
    """Pricing and solving times on the procedural map; PyVRP vs OR-Tools on the same problem."""
    tmap = procedural_map((args.size, args.size), 1.0, seed=args.seed)
    cost = with_spread(CostSpec().build(tmap), args.rel_sd)
    depot, sites = depot_and_sites(cost, args.sites, np.random.default_rng(args.seed))
    pts = np.vstack([depot, sites.xy_m])
    t0 = time.perf_counter()
    prices = price_pairs(cost, pts, ("depot", *sites.names), risk=args.risk, compute=Compute(workers=args.workers))
    pricing_s = time.perf_counter() - t0
    battery = battery_for(prices, args.battery_trips, cost.battery_voltage_v)
    robots = [TourRobot(battery, depot, f"robot {k}") for k in range(args.robots)]
    t0 = time.perf_counter()
    res = plan_tour(cost, sites, robots, prices=prices, search=TourSearch(risk=args.risk, time_limit_s=args.pyvrp_s,
                                                                             improve=args.improve))
    solve_s = time.perf_counter() - t0
    budgets = [r.budget_j for r in robots]
    cands = [k + 1 for k, n in enumerate(sites.names)
             if n in res.visited or res.left_out.get(n, "").startswith("not worth")]
    value = np.concatenate([[0.0], sites.value])
    problem = TourProblem.build(prices, args.risk, budgets, [0] * args.robots, cands,
                                TourPoints(value, np.zeros(len(pts))))
    compare = {}
    for name, solve in (("pyvrp", lambda: solve_pyvrp(problem, args.pyvrp_s, 0)),
                        ("ortools", lambda: solve_ortools(problem, args.ortools_s))):
        t0 = time.perf_counter()
        tours = solve()
        elapsed = time.perf_counter() - t0
        ok = all(problem.tour_units(r, t) <= problem.capacity_units[r] for r, t in enumerate(tours))
        compare[name] = {"value": float(sum(value[p] for t in tours for p in t)), "solve_s": elapsed,
                         "sites": sum(len(t) for t in tours), "feasible": bool(ok)}
    too_far = sum(1 for v in res.left_out.values() if v.startswith("too far"))
    return {"size": args.size, "sites": args.sites, "robots": args.robots, "risk": args.risk, "rel_sd": args.rel_sd,
            "workers": args.workers, "pricing_s": pricing_s, "pricing_where": prices.where, "solve_s": solve_s,
            "total_s": pricing_s + solve_s, "solve_rounds": res.solve_rounds, "value": res.value,
            "sites_added": res.sites_added, "sites_swapped": res.sites_swapped, "improve_s": res.improve_time_s,
            "value_possible": float(sites.value.sum()), "visited": len(res.visited), "too_far": too_far,
            "battery_ah": battery.capacity_ah, "compare": compare}


def fit_estimator(tmap: TerrainMap, seed: int) -> VibrationCurrentEstimator:
    """A small vibration estimator with its cross-validated interval, fitted on 4 simulated runs of 40 s per ground
    of ``tmap`` (the truth simulator, each ground's resistance varying by 15 % along a run)."""
    grounds = sorted(tmap.ground_names.values())
    truth = TruthSimulator(robot_preset("husky"), {g: ground_preset(g) for g in grounds}, seed=seed,
                           variation={g: GroundVariation(relative_std=0.15, length_scale_m=20.0) for g in grounds})
    t = np.arange(0.0, 40.0, 0.01)
    logs = []
    for gi, g in enumerate(grounds):
        for s in range(4):
            p1, p2 = np.random.default_rng(seed + 100 * gi + s).uniform(0, 2 * np.pi, 2)
            v = 0.45 + 0.3 * np.sin(2 * np.pi * t / 7.0 + p1)
            w = 0.5 * np.sin(2 * np.pi * t / 5.0 + p2)
            logs.append(truth.run_commands(t, v, w, ground=g, seed=seed + 100 * gi + s).log)
    cfg = estimator_preset("default").replace(window_s=0.5, hidden_sizes=(16, 16), n_members=3, max_epochs=25,
                                              patience=8, learning_rate=3e-3, batch_size=64, train_stride_s=0.3,
                                              dropout=0.0)
    return VibrationCurrentEstimator(cfg, seed=seed, n_threads=1).fit(logs)


def monte_carlo_part(args: argparse.Namespace) -> dict[str, Any]:
    """The tours at Q = 0.9 and 0.5 on the bundled map, each driven ``args.mc`` times."""
    tmap: TerrainMap = example_map()
    if args.model is not None:
        cost = CostSpec(model=load_current_model(args.model)).build(tmap)
        interval = f"model {args.model.name}"
    elif not args.stated_spread:
        t0 = time.perf_counter()
        cost = CostSpec(model=fit_estimator(tmap, args.seed)).build(tmap)
        interval = (f"a vibration estimator fitted on simulated runs of the map's grounds, its interval "
                    f"({time.perf_counter() - t0:.0f} s to fit and price)")
    else:
        cost = with_spread(CostSpec().build(tmap), args.rel_sd)
        interval = f"presets with a stated run-level spread of {args.rel_sd:g} of the mean"
    depot, sites = depot_and_sites(cost, args.mc_sites, np.random.default_rng(args.seed + 1))
    first = None
    out: dict[str, Any] = {"map": "bundled example map", "interval": interval, "sites": args.mc_sites,
                           "robots": 2, "missions_per_robot": args.mc}
    for q in (0.9, 0.5):
        if first is None:
            prices = price_pairs(cost, np.vstack([depot, sites.xy_m]), ("depot", *sites.names), risk=0.9)
            battery = battery_for(prices, args.mc_battery_trips, cost.battery_voltage_v)
            robots = [TourRobot(battery, depot, f"robot {k}") for k in range(2)]
            first = prices
        res = plan_tour(cost, sites, robots, prices=first, search=TourSearch(risk=q, improve=args.improve))
        check = simulate_tours_mc(res, args.mc, seed=args.seed)
        out[f"q{q:g}"] = {"value": res.value, "visited": len(res.visited), "sites_added": res.sites_added,
                          "sites_swapped": res.sites_swapped, "improve_s": res.improve_time_s,
                          "share_above_reserve": check.share_above_reserve,
                          "energy_at_q_wh": [t.energy_at_risk_j / 3600 for t in res.tours],
                          "budget_wh": [t.budget_j / 3600 for t in res.tours]}
    return out


def chargers_part(args: argparse.Namespace) -> dict[str, Any]:
    """Value without and with charging points on the bundled map (stated spread), solve times, the Monte Carlo."""
    cost = with_spread(CostSpec().build(example_map()), args.rel_sd)
    depot, sites = depot_and_sites(cost, args.charger_sites, np.random.default_rng(args.seed + 2))
    _, spots = depot_and_sites(cost, args.chargers, np.random.default_rng(args.seed + 3))
    chargers = TourChargers(tuple(f"charger{k}" for k in range(args.chargers)), spots.xy_m, power_w=200.0,
                            connection_time_s=60.0, max_visits=2)
    pts = np.vstack([depot, sites.xy_m, chargers.xy_m])
    t0 = time.perf_counter()
    prices = price_pairs(cost, pts, ("depot", *sites.names, *chargers.names), risk=0.9)
    pricing_s = time.perf_counter() - t0
    battery = battery_for(prices, args.charger_battery_trips, cost.battery_voltage_v)
    robots = [TourRobot(battery, depot, f"robot {k}") for k in range(2)]
    alone_prices = price_pairs(cost, pts[:-args.chargers], ("depot", *sites.names), risk=0.9)
    t0 = time.perf_counter()
    alone = plan_tour(cost, sites, robots, prices=alone_prices,
                      search=TourSearch(risk=0.9, time_limit_s=args.pyvrp_s, improve=args.improve))
    alone_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    charged = plan_tour(cost, sites, robots, prices=prices, chargers=chargers,
                        search=TourSearch(risk=0.9, time_limit_s=args.ortools_s, improve=args.improve))
    charged_s = time.perf_counter() - t0
    check = simulate_tours_mc(charged, args.mc, seed=args.seed)
    worst = min((min(check.share_above_at_stops(name)) for name in check.runs), default=float("nan"))
    return {"map": "bundled example map", "sites": args.charger_sites, "chargers": args.chargers, "robots": 2,
            "rel_sd": args.rel_sd, "battery_ah": battery.capacity_ah, "pricing_s": pricing_s,
            "value_possible": float(sites.value.sum()),
            "without": {"value": alone.value, "visited": len(alone.visited), "solver": alone.solver,
                        "solve_s": alone_s,
                        "too_far": sum(1 for v in alone.left_out.values() if v.startswith("too far"))},
            "with": {"value": charged.value, "visited": len(charged.visited), "solver": charged.solver,
                     "solve_s": charged_s, "rounds": charged.solve_rounds,
                     "charging_stops": sum(len(t.charging_stops) for t in charged.tours),
                     "too_far": sum(1 for v in charged.left_out.values() if v.startswith("too far"))},
            "mc": {"missions_per_robot": args.mc, "share_above_reserve": check.share_above_reserve,
                   "worst_arrival_share": worst}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="map side in cells (default 512)")
    parser.add_argument("--sites", type=int, default=200, help="sites (default 200)")
    parser.add_argument("--robots", type=int, default=3, help="robots (default 3)")
    parser.add_argument("--risk", type=float, default=0.9, help="risk level of the timing part (default 0.9)")
    parser.add_argument("--rel-sd", type=float, default=0.1, help="stated run-level spread, share of the mean (0.1)")
    parser.add_argument("--battery-trips", type=float, default=4.0,
                        help="each robot's budget in median depot round trips to a site (default 4)")
    parser.add_argument("--workers", type=int, default=2, help="dask workers of the pricing (default 2)")
    parser.add_argument("--pyvrp-s", type=float, default=30.0, help="PyVRP time limit (s, default 30)")
    parser.add_argument("--ortools-s", type=float, default=30.0, help="OR-Tools time limit (s, default 30)")
    parser.add_argument("--mc", type=int, default=1000, help="Monte Carlo tours per robot and level (default 1000)")
    parser.add_argument("--mc-sites", type=int, default=40, help="sites of the Monte Carlo part (default 40)")
    parser.add_argument("--mc-battery-trips", type=float, default=1.5,
                        help="the MC part's budget per robot in median depot round trips (default 1.5)")
    parser.add_argument("--model", type=Path, default=None, help="a saved model with an interval for the MC part")
    parser.add_argument("--stated-spread", action="store_true",
                        help="MC part on the presets with --rel-sd instead of a fitted estimator's interval")
    parser.add_argument("--chargers", type=int, default=3, help="charging points of the chargers part (default 3)")
    parser.add_argument("--charger-sites", type=int, default=40, help="sites of the chargers part (default 40)")
    parser.add_argument("--charger-battery-trips", type=float, default=1.0,
                        help="the chargers part's budget per robot in median depot round trips (default 1)")
    parser.add_argument("--parts", default="timing,mc,chargers",
                        help="comma-separated parts to run: timing, mc, chargers (default all)")
    parser.add_argument("--seed", type=int, default=0, help="map, sites and Monte Carlo seed")
    parser.add_argument("--no-improve", dest="improve", action="store_false",
                        help="the solver's tours without the improvement step priced as driven (as measured before it)")
    parser.add_argument("--quick", action="store_true", help="small run: 192^2, 60 sites, 200 missions")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.sites, args.mc, args.pyvrp_s, args.ortools_s = 192, 60, 200, 10.0, 10.0
    parts = set(args.parts.split(","))
    compile_s = warm_up_kernels()
    load_before = os.getloadavg()[0]
    timing = timing_part(args) if "timing" in parts else None
    mc = monte_carlo_part(args) if "mc" in parts else None
    charging = chargers_part(args) if "chargers" in parts else None
    load = (load_before + os.getloadavg()[0]) / 2
    rows = []
    if timing is not None:
        print(f"\n{timing['sites']} sites, {timing['robots']} robots, {timing['size']}^2 map, Q = {timing['risk']:g}, "
              f"pricing on {timing['workers']} worker(s) ({timing['pricing_where']})")
        rows += [("pair pricing", f"{timing['pricing_s']:.1f} s"),
                 ("solving (PyVRP, checked)", f"{timing['solve_s']:.1f} s ({timing['solve_rounds']} round(s); the "
                                              f"improvement step {timing['improve_s']:.1f} s of it, "
                                              f"{timing['sites_added']} sites added, {timing['sites_swapped']} "
                                              "swapped in)"),
                 ("total", f"{timing['total_s']:.1f} s (target <= 120 s)"),
                 ("value", f"{timing['value']:g} of {timing['value_possible']:g} ({timing['visited']} sites; "
                           f"{timing['too_far']} too far at Q)")]
        for name, r in timing["compare"].items():
            rows.append((f"{name}", f"value {r['value']:g} ({r['sites']} sites) in {r['solve_s']:.1f} s, "
                                    f"feasible {r['feasible']}"))
    if mc is not None:
        for q in ("q0.9", "q0.5"):
            m = mc[q]
            rows.append((f"MC at Q = {q[1:]}", f"{100 * m['share_above_reserve']:.1f} % end above the reserve "
                                               f"(value {m['value']:g}, {m['visited']} sites, "
                                               f"{m['sites_added']} added and {m['sites_swapped']} swapped in by "
                                               f"the improvement step)"))
    if charging is not None:
        c = charging
        for key, label in (("without", "no chargers"), ("with", f"{c['chargers']} chargers")):
            r = c[key]
            rows.append((label, f"value {r['value']:g} of {c['value_possible']:g} ({r['visited']} sites, "
                                f"{r['too_far']} too far; {r['solver']} {r['solve_s']:.1f} s)"
                                + (f", {r['charging_stops']} charging stops" if key == "with" else "")))
        rows.append(("MC with charges, Q = 0.9", f"{100 * c['mc']['share_above_reserve']:.1f} % above the reserve "
                                                 f"at every arrival and back (worst single arrival "
                                                 f"{100 * c['mc']['worst_arrival_share']:.1f} %)"))
    width = max(len(n) for n, _ in rows)
    for name, value in rows:
        print(f"{name:<{width}}  {value}")
    if mc is not None:
        print(f"(MC on the {mc['map']}: {mc['interval']}; {mc['missions_per_robot']} tours per robot and level)")
    print(f"(1-minute load average during the run: about {load:.1f} on {os.cpu_count()} cores)")
    if args.out is not None:
        payload = {"benchmark": "tour_bench", "seed": args.seed, "kernel_compile_s": compile_s, "timing": timing,
                   "monte_carlo": mc, "chargers": charging,
                   "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                               "platform": platform.platform(), "load_average_1min": load}}
        write_json_atomic(args.out, payload, indent=1)
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
