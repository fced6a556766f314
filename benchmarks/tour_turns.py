"""Tour turns benchmark: what a tour's forecast misses by pricing its legs one by one, and what the robot drives.

A tour's legs are priced apart (:func:`planner.tours.price_pairs`: each from a free heading); the robot drives them
joined, turning in place at every stop. On four cases (maps, sites and robots apart) this prints, per tour segment
(from the depot or a charge to the next charge or back): the sum of its legs' prices, the joined route's price
(:func:`planner.price_route`), their difference split into the turns at the stops (the joined route's turn energy at
each junction of two legs) and the rest, the tour's reported energy (mean and at Q) and, on the three Husky cases,
the share of the planned tours that end above the reserve when the mission simulator drives them with drawn
parameters (:func:`planner.tours.simulate_tours_mc`, ``draw_from="parameters"``) beside Q.

Each case is planned twice on the same legs: the solver's tours alone (``TourSearch(improve=False)``) and after the
improvement step priced as driven (:func:`planner.tours.improve_tours`); it prints the value before and after, the
sites the step added, each tour's share of its budget at Q priced as driven, how many left-out sites would each still
fit into one of the tours (inserted at their best position, priced as driven), and the solver's and the step's times.
Case 5 (``--cases 5``, not run by default: about a minute of pricing) is ``tour_bench.py``'s binding-battery instance:
a 256 x 256 procedural map, 100 sites, 3 Husky robots of 2 median round trips each.

Run it on the code before and after a change with the same arguments to compare. Usage::

    python benchmarks/tour_turns.py --mc 20 --seeds 0 1 --out tour_turns.json
    python benchmarks/tour_turns.py --cases 5 --mc 0
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from energy import Battery
from planner import CostTables, EnergyCost, price_route
from planner.cost_spec import CostSpec
from planner.tours import (
    DrivenPricer,
    TourChargers,
    TourRobot,
    TourSearch,
    TourSites,
    plan_tour,
    price_pairs,
    simulate_tours_mc,
)
from terrain import TerrainMap, example_map
from terrain.procedural import procedural_map
from terrawatt_base.atomic import write_json_atomic


def with_spread(cost: EnergyCost, rel_sd: float) -> EnergyCost:
    """``cost`` with a run-level spread of ``rel_sd`` of every mean table entry (drive and turns)."""
    t = cost.tables
    sd = np.nan_to_num(np.abs(rel_sd * t.grade_table_j_per_m), nan=0.0, posinf=0.0)
    return cost.with_tables(CostTables(t.grade_table_j_per_m, t.turn_table_j, ground_labels=t.ground_labels,
                                       grade_sd_table_j_per_m=sd, turn_sd_table_j=np.abs(rel_sd * t.turn_table_j)))


def patch_map() -> TerrainMap:
    """The golden cases' 60 x 24 m patch: a gentle ramp of asphalt, a sand band, a short wall."""
    ground = np.zeros((24, 60), dtype=int)
    ground[6:18, 20:40] = 1
    obstacle = np.zeros((24, 60), dtype=bool)
    obstacle[0:8, 45] = True
    return TerrainMap(np.tile(0.02 * np.arange(60.0), (24, 1)), 1.0, ground=ground,
                      ground_names={0: "asphalt", 1: "sand"}, obstacle=obstacle)


def hills_map() -> TerrainMap:
    """40 x 40 m: two round hills on asphalt, sand on the east half (the tour tests' map)."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    z = 3.0 * np.exp(-((x - 14) ** 2 + (y - 26) ** 2) / 60.0) + 2.0 * np.exp(-((x - 28) ** 2 + (y - 12) ** 2) / 40.0)
    return TerrainMap(z, 1.0, ground=np.where(x > 20, 1, 0), ground_names={0: "asphalt", 1: "sand"})


def free_sites(cost: EnergyCost, n: int, seed: int) -> tuple[tuple[float, float], TourSites]:
    """A depot near the centre of the map's largest free region and ``n`` sites in it, values 1-5."""
    rng = np.random.default_rng(seed)
    labels, _ = ndimage.label(~np.asarray(cost.blocked))
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    free = np.argwhere(labels == int(np.argmax(sizes)))
    xc, yc = cost.terrain.cell_centres()
    d = free[np.argmin(np.hypot(*(free - np.array(cost.shape) / 2).T))]
    pick = free[rng.choice(len(free), n, replace=False)]
    return (float(xc[d[1]]), float(yc[d[0]])), TourSites(
        tuple(f"s{k:02d}" for k in range(n)), np.column_stack([xc[pick[:, 1]], yc[pick[:, 0]]]),
        value=rng.integers(1, 6, n).astype(float))


def cases() -> dict[str, dict[str, Any]]:
    """The four cases: the golden ``tour_chargers`` inputs, the hills, the bundled map, a Jackal on a procedural map."""
    out: dict[str, dict[str, Any]] = {}
    cost = CostSpec().build(patch_map())
    out["golden tour_chargers"] = dict(
        cost=cost, sites=TourSites(("pump", "shed", "well"), [[10.5, 20.5], [55.5, 20.5], [50.5, 5.5]],
                                   value=[2, 3, 1]),
        robots=[TourRobot(Battery(0.08, 24.0, min_reserve_pct=20.0), (3.5, 12.5))], mc=True,
        chargers=TourChargers(("dock",), [[36.5, 21.5]], power_w=60.0, connection_time_s=15.0, max_visits=2),
        search=TourSearch(risk=0.9, time_limit_s=1.0))
    cost = with_spread(CostSpec().build(hills_map()), 0.15)
    rng = np.random.default_rng(9)
    out["hills, 8 sites"] = dict(
        cost=cost, sites=TourSites(tuple(f"s{k}" for k in range(8)), rng.uniform(3.0, 37.0, size=(8, 2)),
                                   value=rng.integers(1, 6, 8).astype(float)),
        robots=[TourRobot(Battery(0.12, 24.0, min_reserve_pct=20.0), (20.0, 20.0))], mc=True,
        search=TourSearch(risk=0.9, seed=1))
    cost = with_spread(CostSpec().build(example_map()), 0.1)
    depot, sites = free_sites(cost, 14, 1)
    out["bundled map, 14 sites, 2 robots"] = dict(
        cost=cost, sites=sites, mc=True, search=TourSearch(risk=0.9, seed=0),
        robots=[TourRobot(Battery(0.6, 24.0, min_reserve_pct=20.0), depot, f"robot {k}") for k in range(2)])
    cost = with_spread(CostSpec(robot="jackal").build(procedural_map((128, 128), 1.0, seed=3)), 0.1)
    depot, sites = free_sites(cost, 12, 2)
    out["jackal, procedural 128^2, 12 sites"] = dict(
        cost=cost, sites=sites, mc=False, search=TourSearch(risk=0.9, seed=0),
        robots=[TourRobot(Battery(0.25, 25.6, min_reserve_pct=20.0), depot)])
    return out


def large_case(seed: int = 0) -> dict[str, Any]:
    """Case 5: tour_bench.py's binding battery (``--size 256 --sites 100 --battery-trips 2 --pyvrp-s 10``; its
    ``--seed``: the map's and the sites')."""
    from tour_bench import battery_for, depot_and_sites  # the benchmarks' folder is the script's

    cost = with_spread(CostSpec().build(procedural_map((256, 256), 1.0, seed=seed)), 0.1)
    depot, sites = depot_and_sites(cost, 100, np.random.default_rng(seed))
    prices = price_pairs(cost, np.vstack([depot, sites.xy_m]), ("depot", *sites.names), risk=0.9)
    battery = battery_for(prices, 2.0, cost.battery_voltage_v)
    return dict(cost=cost, sites=sites, mc=False, search=TourSearch(risk=0.9, time_limit_s=10.0), prices=prices,
                robots=[TourRobot(battery, depot, f"robot {k}") for k in range(3)])


def still_fit(res: Any) -> list[str]:
    """The left-out sites ("not worth it") that would each fit into one of the tours, inserted at their best position
    and priced as driven (:class:`planner.tours.DrivenPricer`; tours without chargers, service or windows)."""
    prices, q = res.prices, res.risk
    pricer = DrivenPricer.of(prices, q)
    index = {n: k for k, n in enumerate(prices.names)}
    none = np.zeros(len(prices), dtype=bool)
    out = []
    for name, why in res.left_out.items():
        if not why.startswith("not worth"):
            continue
        u = index[name]
        for tour in res.tours:
            d = index[tour.legs[0].start] if tour.legs else index[prices.names[0]]
            stops = [index[s] for s in tour.stops]
            seqs = np.array([[d, *stops[:k], u, *stops[k:], d] for k in range(len(stops) + 1)])
            if float(pricer.segments(seqs, none)[2][:, 0].min()) <= tour.budget_j:
                out.append(name)
                break
    return out


def used(res: Any) -> list[float]:
    """Each tour's share of its budget at Q priced as driven (its fullest segment; 0 for a robot left home)."""
    return [max(iv.quantile_j(res.risk) / b for iv, b in zip(t.segments, t.segment_budgets_j)) if t.legs else 0.0
            for t in res.tours]


def split(res: Any, k: int) -> list[dict[str, Any]]:
    """Per segment of tour ``k`` between charges: the legs' prices summed, the joined route's price, the turns at
    its stops (the joined route's turn energy at each junction of two legs) and the rest of the difference (J)."""
    cost, tour = res.cost, res.tours[k]
    ends = [*tour.charging_stops, len(tour.legs) - 1]
    rows, first = [], 0
    for end in ends:
        legs = tour.legs[first:end + 1]
        pts = np.vstack([legs[0].waypoints_m] + [leg.waypoints_m[1:] for leg in legs[1:]])
        junctions = np.cumsum([len(leg.waypoints_m) - 1 for leg in legs[:-1]])
        _, turns = cost.turn_energies_j(pts)
        legs_j = float(sum(price_route(cost, leg.waypoints_m, interval=False).mean_j for leg in legs))
        joined_j = price_route(cost, pts, interval=False).mean_j
        at_stops = float(turns[junctions].sum()) if junctions.size else 0.0
        rows.append({"to": legs[-1].end, "legs_j": legs_j, "joined_j": joined_j, "turns_at_stops_j": at_stops,
                     "rest_j": joined_j - legs_j - at_stops, "stops": len(legs) - 1})
        first = end + 1
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mc", type=int, default=20, help="simulated drives of each tour per seed (default 20)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1], help="Monte Carlo seeds (default 0 1)")
    parser.add_argument("--cases", nargs="*", default=None, help="case numbers to run (1-5; default 1-4)")
    parser.add_argument("--large-seed", type=int, default=0, help="case 5's map and sites seed (default 0)")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    results = []
    chosen = args.cases or ["1", "2", "3", "4"]
    every = cases()
    if "5" in chosen:
        every["procedural 256^2, 100 sites, 3 robots"] = large_case(args.large_seed)
    for n, (name, case) in enumerate(every.items(), start=1):
        if str(n) not in chosen:
            continue
        t0 = time.perf_counter()
        kept = plan_tour(case["cost"], case["sites"], case["robots"], prices=case.get("prices"),
                         search=dataclasses.replace(case["search"], improve=False), chargers=case.get("chargers"))
        res = plan_tour(case["cost"], case["sites"], case["robots"], prices=kept.prices, search=case["search"],
                        chargers=case.get("chargers"))
        plan_s = time.perf_counter() - t0
        q = res.risk

        step = {"value_before": kept.value, "value_after": res.value, "sites_before": len(kept.visited),
                "sites_after": len(res.visited), "sites_added": res.sites_added, "solve_s": res.solve_time_s,
                "step_s": res.improve_time_s, "budget_used_before": used(kept), "budget_used_after": used(res),
                "left_out_before": sum(why.startswith("not worth") for why in kept.left_out.values()),
                "left_out_after": sum(why.startswith("not worth") for why in res.left_out.values()),
                "still_fit_before": len(still_fit(kept)) if case.get("chargers") is None else None,
                "still_fit_after": len(still_fit(res)) if case.get("chargers") is None else None}
        print(f"\n{n}. {name}: value {kept.value:g} -> {res.value:g} ({len(kept.visited)} -> {len(res.visited)} "
              f"sites, {res.sites_added} added by the step), solved in {res.solve_time_s:.2f} s "
              f"({res.solve_rounds} round(s)), step {res.improve_time_s:.3f} s, planned twice in {plan_s:.1f} s")
        print("  budget used at Q as driven: " + ", ".join(f"{100 * a:.1f} -> {100 * b:.1f} %" for a, b in
                                                          zip(step["budget_used_before"], step["budget_used_after"]))
              + f"; left out (not worth it) {step['left_out_before']} -> {step['left_out_after']}, of which would "
              f"each still fit {step['still_fit_before']} -> {step['still_fit_after']}")
        tours = []
        for k, tour in enumerate(res.tours):
            if not tour.legs:
                continue
            rows = split(res, k)
            seg_q = [iv.quantile_j(q) for iv in tour.segments]
            print(f"  {tour.robot}: depot -> {' -> '.join(tour.stops)} -> depot; reported {tour.energy.mean_j:.0f} J, "
                  f"segments at Q {', '.join(f'{s:.0f}' for s in seg_q)} of {tour.budget_j:.0f} J")
            for r in rows:
                print(f"    to {r['to']:<6} legs {r['legs_j']:7.0f} J  joined {r['joined_j']:7.0f} J "
                      f"(+{100 * (r['joined_j'] / r['legs_j'] - 1):4.1f} %)  turns at {r['stops']} stop(s) "
                      f"{r['turns_at_stops_j']:6.0f} J  rest {r['rest_j']:6.1f} J")
            tours.append({"robot": tour.robot, "stops": list(tour.stops), "segments": rows,
                          "reported_mean_j": tour.energy.mean_j, "reported_segments_at_q_j": seg_q,
                          "budget_j": tour.budget_j})
        shares, driven = [], []
        if case["mc"] and args.mc > 0 and res.tours and any(t.legs for t in res.tours):
            for seed in args.seeds:
                check = simulate_tours_mc(res, args.mc, seed=seed, draw_from="parameters")
                shares.append(check.share_above_reserve)
                if not driven:  # per segment: the stop-turn-go profile's forecast and the simulated median (J)
                    driven = [(mc.predicted_energy_j, float(np.nanmedian(mc.energy_j)))
                              for studies in check.runs.values() for mc in studies]
            print(f"  above the reserve (drawn parameters, {args.mc} drives x seeds {args.seeds}): "
                  + ", ".join(f"{100 * s:.1f} %" for s in shares) + f" at Q = {q:g}")
            print("  per segment, the study's forecast (the driven profile with the physics model, else the edges) / the "
                  "simulated median (seed "
                  f"{args.seeds[0]}): " + ", ".join(f"{p:.0f} / {m:.0f} J" for p, m in driven))
        results.append({"case": name, "step": step, "value": res.value, "visited": list(res.visited), "rounds": res.solve_rounds,
                        "solve_s": res.solve_time_s, "tours": tours, "mc_shares": shares,
                        "profile_and_simulated_median_j": driven})
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "tour_turns", "mc": args.mc, "seeds": args.seeds,
                                     "cases": results}, indent=1)
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
