"""Tour stops benchmark: the tours' Monte Carlo check against the plan where a site lies on the line between its neighbours.

The plan prices a stop-and-go at every site (the robot stops to serve it), also where it leaves on the heading it
arrived on; the check's simulated drive (:func:`planner.tours.simulate_tours_mc` with drawn parameters) stops there
too (``MissionDrive(stops=...)``). On a flat 20 m x 60 m corridor with a Jackal and fixed draws (no payload, fade,
resistance, ground or speed factor: the plan alone), this prints per tour the plan's mean energy, the simulated mean,
their gap, and the same route driven through its collinear sites (as the check drove it before its stops): its gap
and what stopping at those sites adds (energy and time), beside the plan's stop-and-go price.

Usage::

    python benchmarks/tour_stops.py --mc 2 --out tour_stops.json
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from energy import Battery
from planner.cost_spec import CostSpec
from planner.missions import MissionDistributions, MissionTruth, MonteCarloStudy, simulate_missions_mc
from planner.tours import TourRobot, TourSearch, TourSites, plan_tour, simulate_tours_mc
from terrain import flat_map
from terrawatt_base.atomic import write_json_atomic

#: The tours: sites (names, x, y in m) visited from a depot at (2, 10) m on the corridor's axis y = 10 m.
CASES = {
    "far site alone (a U-turn)": (("far",), [[50.0, 10.0]]),
    "one site on the line": (("mid", "far"), [[25.0, 10.0], [50.0, 10.0]]),
    "two sites on the line": (("a", "b", "far"), [[17.0, 10.0], [33.0, 10.0], [50.0, 10.0]]),
    "one site off the line": (("mid", "far"), [[25.0, 14.0], [50.0, 10.0]]),
    "a triangle": (("mid", "far"), [[25.0, 3.0], [50.0, 16.0]]),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mc", type=int, default=2, help="drives per tour (default 2; the draws are fixed)")
    parser.add_argument("--seed", type=int, default=1, help="the check's seed")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    cost = CostSpec(robot="jackal").build(flat_map((20, 60), 1.0))
    fixed = MissionDistributions(ground_coef_scale=(1.0, 1.0), payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0),
                                 internal_resistance_ohm=(0.0, 0.0), speed_scale=(1.0, 1.0))
    stop_go_j = float(cost.stop_go_at(np.array([0]))[0])
    rows = []
    for label, (names, xy) in CASES.items():
        res = plan_tour(cost, TourSites(names, xy), TourRobot(Battery(0.3, 12.0), (2.0, 10.0)),
                        search=TourSearch(risk=0.9, time_limit_s=1.0))
        tour = res.tours[0]
        (mc,) = simulate_tours_mc(res, args.mc, seed=args.seed, distributions=fixed).runs[tour.robot]
        through = simulate_missions_mc(res.terrain, res.tour_route(0), tour.battery,
                                       MonteCarloStudy(args.mc, seed=args.seed, distributions=fixed),
                                       truth=MissionTruth(robot="jackal"), cost=cost)
        sim = float(np.mean(mc.energy_j))
        rows.append({"tour": label, "stops": list(tour.stops), "plan_mean_j": tour.energy.mean_j, "sim_mean_j": sim,
                     "gap_pct": 100.0 * (sim / tour.energy.mean_j - 1.0),
                     "through_gap_pct": 100.0 * (float(np.mean(through.energy_j)) / tour.energy.mean_j - 1.0),
                     "stop_energy_j": float(np.mean(mc.energy_j - through.energy_j)),
                     "stop_time_s": float(np.mean(mc.duration_s - through.duration_s))})
    print(f"{'tour':<26} {'stops':<16} {'plan J':>8} {'sim J':>8} {'gap':>7} {'through':>8} {'stopping adds':>18}")
    for r in rows:
        print(f"{r['tour']:<26} {' '.join(r['stops']):<16} {r['plan_mean_j']:8.1f} {r['sim_mean_j']:8.1f} "
              f"{r['gap_pct']:+6.2f}% {r['through_gap_pct']:+7.2f}% {r['stop_energy_j']:8.1f} J {r['stop_time_s']:5.2f} s")
    print(f"(the plan's stop-and-go on this ground: {stop_go_j:.1f} J; {args.mc} drive(s) per tour, fixed draws; "
          "'through': the same route driven through its collinear sites)")
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "tour_stops", "mc": args.mc, "seed": args.seed,
                                     "stop_go_j": stop_go_j, "tours": rows}, indent=1)
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
