"""Planner vs simulator gap benchmark: a route's price against the mission simulator driving it, split by cause.

On fixed routes (flat and over the hills of ``hills_map()``, on asphalt and sand, one with a turn, the hills tour
of ``tour_turns.py`` and the golden ``tour_chargers`` shed segment) this drives each route with the mission
simulator (:func:`planner.simulate_mission` against a :class:`energy.TruthSimulator` of the same robot and ground
presets the planner priced, **no drawn parameters**) and walks from what a Monte Carlo mission books down to the
planner's edge price (:func:`planner.price_route`), switching one cause off at a time (each step keeps the ones
before it off). Per route, in J (the step's change of the simulated energy):

- ``payload``: the Monte Carlo default draw's mean payload (10 kg of ``MissionDistributions().payload_kg``,
  (0, 20) kg) against none (the planner prices the robot without payload);
- ``noise``: the current sensor's noise, outliers, quantisation and rest offset (``NoiseModel()`` -> ``off()``);
- ``slip_unbooked``: the energy the mission books from the logged currents (:func:`energy.budget.log_battery_power_w`,
  motor speed from the logged speeds, no wheel slip) -> the simulator's own battery power (negative: the slip loss
  the booking does not see);
- ``velocity_lag``: the simulator's first-order velocity tracking (0.1 s) -> none;
- ``sampling``: the simulator's 100 Hz against the forecast's 20 Hz profile;
- ``starts_and_stops``, ``turn_ramps``: what starting and stopping every driven segment (the ramps' seconds at the
  electronics' power, the kinetic energy, the control board's start-up) and ramping the yaw rate of every pivot add
  to steady driving and steady pivots, priced by the physics model on the profile (:func:`profile_parts`);
- ``priced``: what the edges price for them (the edge price less the steady one: segments at the steady energy per
  metre, pivots at ``turn_energy_j``), the stop-turn-go turn tables of :func:`planner.tables.stop_turn_go_rows`;
- ``rest``: the stop-turn-go forecast (``price_route(how="profile")``) less the edge price: the slope convention
  (a driven profile advances its pose by the commanded speed in the *horizontal* plane, the tables charge the
  *surface* length), the bilinear slope under each pose against the tables' per-cell grade, the stop-and-go on a
  grade (the tables price it on level ground) and the forecast's 20 Hz sampling.

The forecast is the physics model that priced the tables on the profile the simulator drives. Separately it prints the pack's internal resistance (the default draw's
mean 0.05 ohm) as charge: the energy booked is the terminal energy, the reserve is a state of charge.

With ``--mc N`` it also drives the tours of ``tour_turns.py``'s three Husky cases N times per seed, as
:func:`planner.tours.simulate_tours_mc` does with drawn parameters (each segment between charges from the charge it
starts with, mission ``i`` of every segment drawing the same parameters), once with the default draws
(:class:`planner.MissionDistributions`) and then with the draws fixed at the priced robot one group at a time:
no payload, then no capacity fade either, then every parameter nominal; it prints the share of tours above the
reserve at every arrival and the segments' median energy.

Usage::

    python benchmarks/sim_gap.py --out sim_gap.json
    python benchmarks/sim_gap.py --mc 40 --seeds 0 1 2
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import tour_turns  # the hills map and the tour cases (benchmarks/ is the script's directory)

from energy import Battery, TruthSimulator, drive_profile, ground_preset, robot_preset
from energy.profiles import drivable_waypoints
from energy.sim import NoiseModel
from planner import CostSpec, MissionDistributions, price_route, simulate_mission
from planner.missions.options import MissionDrive
from planner.route import evaluate_route
from planner.tours import plan_tour, simulate_tours_mc
from terrain import flat_map
from terrawatt_base.atomic import write_json_atomic

#: The simulator's causes, switched off in this order (the mission's booking down to the physics on the profile).
SIM_STEPS = ("payload", "noise", "slip_unbooked", "velocity_lag", "sampling")
#: The parts of the stop-turn-go profile beyond steady driving, what the edges price for them, then what is left.
PROFILE_STEPS = ("starts_and_stops", "turn_ramps", "priced", "rest")
RATE_HZ = 100.0
DT_S = 0.01


def routes() -> dict[str, tuple[Any, np.ndarray]]:
    """The routes: (map, waypoints) by name."""
    hills = tour_turns.hills_map()
    asphalt, sand = flat_map((12, 40), 1.0, ground="asphalt"), flat_map((12, 40), 1.0, ground="sand")
    out = {
        "flat asphalt, 35 m": (asphalt, [[2.5, 5.5], [37.5, 5.5]]),
        "flat sand, 7 m": (sand, [[2.5, 5.5], [9.5, 5.5]]),
        "flat asphalt, a right angle": (asphalt, [[2.5, 1.5], [20.5, 1.5], [20.5, 10.5]]),
        "flat asphalt, a U-turn": (asphalt, [[2.5, 5.5], [20.5, 5.5], [2.5, 5.5]]),
        "up the 3 m hill (asphalt)": (hills, [[5.5, 26.5], [14.5, 26.5]]),
        "down the 3 m hill (asphalt)": (hills, [[14.5, 26.5], [5.5, 26.5]]),
        "over the 3 m hill (asphalt)": (hills, [[2.5, 26.5], [19.5, 26.5]]),
        "over the 2 m hill (sand)": (hills, [[21.5, 12.5], [37.5, 12.5]]),
    }
    for label, name, seg in (("hills tour (tour_turns case 2)", "hills, 8 sites", None),
                             ("golden tour_chargers, shed segment", "golden tour_chargers", (2, 4))):
        case = tour_turns.cases()[name]
        res = plan_tour(case["cost"], case["sites"], case["robots"], search=case["search"],
                        chargers=case.get("chargers"))
        route = res.tour_route(0) if seg is None else res.tour_route(0, slice(*seg))
        out[label] = (res.terrain, route.waypoints_m)
    return {k: (m, np.asarray(w, dtype=np.float64)) for k, (m, w) in out.items()}


def drive(tmap: Any, wp: np.ndarray, *, payload_kg: float = 0.0, noise: NoiseModel | None = None,
          truth_power: bool = False, lag_s: float = 0.1, internal_resistance_ohm: float = 0.0) -> tuple[float, float]:
    """The energy (J) and charge (mAh) the mission simulator books for one drive of ``wp`` at 0.5 m/s."""
    robot = robot_preset("husky")
    robot = robot.replace(mass_kg=robot.mass_kg + payload_kg)
    grounds = {n: ground_preset(n) for n in set(tmap.ground_names.values())}
    sim = TruthSimulator(robot, grounds, noise=NoiseModel() if noise is None else noise,
                         velocity_time_constant_s=lag_s, current_rate_hz=RATE_HZ, seed=0)
    route = evaluate_route(CostSpec(robot=robot).build(tmap), wp)
    m = simulate_mission(tmap, route, robot, Battery(20.0, 24.0, internal_resistance_ohm=internal_resistance_ohm),
                         sim, drive=MissionDrive(speed_mps=0.5, seed=0))
    return (m.truth_energy_j if truth_power else m.budget.actual_energy_j), m.budget.actual_charge_mah


def profile_parts(cost: Any, wp: np.ndarray) -> tuple[float, float]:
    """What starting and stopping each driven segment and ramping the yaw rate of each pivot add to steady driving (J).

    Priced by the physics model that priced ``cost`` on flat ground of the segment's (the turn's) first cell: a
    segment's stop-turn-go drive from rest to rest less its length at the steady energy per metre, a pivot's ramped
    profile less the steady turn energy. Collinear waypoints are driven through (:func:`energy.drivable_waypoints`).
    """
    model, speed, rate = cost.physics_model, cost.speed_mps, cost.turn_rate_radps
    wp, _ = drivable_waypoints(wp)
    r, c = cost.terrain.rowcol(wp[:, 0], wp[:, 1])
    grounds = [cost.ground_params[k] for k in np.asarray(cost.ground_rows)[r, c]]
    lengths = np.hypot(*np.diff(wp, axis=0).T)
    stops = 0.0
    for length, ground in zip(lengths, grounds[:-1]):
        if length > 0:
            p = drive_profile(np.array([[0.0, 0.0], [length, 0.0]]), speed, turn_rate_radps=rate, dt_s=DT_S)
            stops += model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground)
            stops -= length * float(model.energy_per_metre_j(speed, 0.0, ground))
    angles, _ = cost.turn_energies_j(wp)
    ramps = 0.0
    for angle, ground in zip(angles, grounds):
        if angle > 0:
            tip = 1e-6 * np.array([[0.0, 0.0], [np.cos(angle), np.sin(angle)]])
            p = drive_profile(tip, speed, turn_rate_radps=rate, dt_s=DT_S, start_heading_rad=0.0)
            ramps += model.energy_j(p.time_s, p.v_mps, p.omega_radps, ground) - float(model.turn_energy_j(angle, ground))
    return stops, ramps


def steady_price(cost: Any, wp: np.ndarray) -> float:
    """The edge price before the stop-turn-go tables (J): segments at the steady energy per metre, pivots steady."""
    angles, _ = cost.turn_energies_j(wp)
    r, c = cost.terrain.rowcol(wp[:, 0], wp[:, 1])
    rows = np.asarray(cost.ground_rows)[r, c]
    turns = sum(float(cost.physics_model.turn_energy_j(a, cost.ground_params[k])) for a, k in zip(angles, rows))
    return float(cost.segment_energy_j(wp[:-1], wp[1:]).sum()) + turns


def gap(tmap: Any, wp: np.ndarray) -> dict[str, Any]:
    """One route: the edge price, the profile forecast, the simulated energy at each step and the step changes."""
    cost = CostSpec().build(tmap)
    edges = price_route(cost, wp, interval=False).mean_j
    profile = price_route(cost, wp, how="profile", interval=False).mean_j
    off = NoiseModel.off()
    chain = [
        drive(tmap, wp, payload_kg=10.0),
        drive(tmap, wp),
        drive(tmap, wp, noise=off),
        drive(tmap, wp, noise=off, truth_power=True),
        drive(tmap, wp, noise=off, truth_power=True, lag_s=0.0),
    ]
    energies = [e for e, _ in chain] + [profile]
    steps = {name: energies[k] - energies[k + 1] for k, name in enumerate(SIM_STEPS)}
    stops, ramps = profile_parts(cost, wp)
    steady = steady_price(cost, wp)
    steps.update(starts_and_stops=stops, turn_ramps=ramps, priced=edges - steady, rest=profile - edges)
    charge_r = drive(tmap, wp, internal_resistance_ohm=0.05)[1]
    return {"steady_edges_j": steady, "edges_j": edges, "profile_j": profile, "simulated_nominal_j": energies[1],
            "simulated_payload_10kg_j": energies[0], "steps_j": steps,
            "charge_mah": chain[1][1], "charge_with_0.05_ohm_mah": charge_r,
            "segments": int(np.count_nonzero(np.hypot(*np.diff(wp, axis=0).T) > 0)),
            "driven_segments": len(drivable_waypoints(wp)[1])}


#: The draws of the Monte Carlo part, from the default to the priced robot, one group at a time.
DRAWS = {
    "default draws": None,
    "no payload": MissionDistributions(payload_kg=(0.0, 0.0)),
    "no payload, no fade": MissionDistributions(payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0)),
    "every parameter nominal": MissionDistributions((1.0, 1.0), (0.0, 0.0), (0.0, 0.0), (0.0, 0.0), (1.0, 1.0)),
}
MC_CASES = ("golden tour_chargers", "hills, 8 sites", "bundled map, 14 sites, 2 robots")


def tour_shares(case: dict[str, Any], n: int, seeds: list[int]) -> dict[str, Any]:
    """Per draw of :data:`DRAWS`: the share (%) of a case's tours above the reserve at every arrival, per seed, and
    the segments' median energy (J, first seed): :func:`planner.tours.simulate_tours_mc` with the truth simulator."""
    res = plan_tour(case["cost"], case["sites"], case["robots"], search=case["search"], chargers=case.get("chargers"))
    out = {}
    for label, draws in DRAWS.items():
        shares, medians = [], []
        for seed in seeds:
            check = simulate_tours_mc(res, n, seed=seed, draw_from="parameters", distributions=draws)
            shares.append(100.0 * check.share_above_reserve)
            if seed == seeds[0]:
                medians += [float(np.nanmedian(mc.energy_j)) for studies in check.runs.values() for mc in studies]
        out[label] = {"above_reserve_pct": shares, "segment_medians_j": medians}
    return {"risk": res.risk, "reported_segments_j": [iv.mean_j for t in res.tours for iv in t.segments],
            "draws": out}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    parser.add_argument("--mc", type=int, default=0, help="simulated drives of each tour per seed and draw (default 0: "
                        "no Monte Carlo)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="Monte Carlo seeds (default 0 1 2)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    rows = {}
    head = (f"{'route':36s} {'seg':>3s} {'steady':>7s} {'edges':>7s} {'profile':>7s} {'sim':>7s} {'+10kg':>7s} | "
            + " ".join(f"{s[:9]:>9s}" for s in (*SIM_STEPS, *PROFILE_STEPS)))
    print("J; seg = driven segments; steady = the edge price without the stop-turn-go tables; sim = the mission simulator, "
          "nominal parameters; the steps walk from '+10kg' down to the profile, then the profile's parts beyond steady "
          "driving, what the edges price for them and the profile less the edges\n" + head)
    for name, (tmap, wp) in routes().items():
        r = gap(tmap, wp)
        rows[name] = r
        e = r["edges_j"]
        print(f"{name:36s} {r['driven_segments']:3d} {r['steady_edges_j']:7.0f} {e:7.0f} {r['profile_j']:7.0f} "
              f"{r['simulated_nominal_j']:7.0f} "
              f"{r['simulated_payload_10kg_j']:7.0f} | " + " ".join(f"{v:9.1f}" for v in r["steps_j"].values()))
        print(f"{'':36s}     sim / edges {100 * (r['simulated_nominal_j'] / e - 1):+5.1f} %, profile / edges "
              f"{100 * (r['profile_j'] / e - 1):+5.1f} %, sim / profile {100 * (r['simulated_nominal_j'] / r['profile_j'] - 1):+5.1f} %, "
              f"+10 kg / edges {100 * (r['simulated_payload_10kg_j'] / e - 1):+5.1f} %; charge {r['charge_mah']:.1f} mAh, "
              f"with a 0.05 ohm pack {100 * (r['charge_with_0.05_ohm_mah'] / r['charge_mah'] - 1):+.2f} %")
    tours = {}
    if args.mc > 0:
        cases = tour_turns.cases()
        print(f"\nTours above the reserve at every arrival ({args.mc} drives x seeds {args.seeds}); segment medians (J)")
        for name in MC_CASES:
            tours[name] = r = tour_shares(cases[name], args.mc, args.seeds)
            print(f"{name} (planned at Q = {r['risk']:g}; priced segments "
                  + ", ".join(f"{e:.0f}" for e in r["reported_segments_j"]) + " J)")
            for label, d in r["draws"].items():
                print(f"  {label:24s} {' / '.join(f'{x:5.1f}' for x in d['above_reserve_pct'])} %   medians "
                      + ", ".join(f"{e:.0f}" for e in d["segment_medians_j"]))
    print(f"\n{time.perf_counter() - t0:.0f} s")
    if args.out is not None:
        write_json_atomic(args.out, {"benchmark": "sim_gap", "rate_hz": RATE_HZ, "steps": [*SIM_STEPS, *PROFILE_STEPS],
                                     "routes": rows, "mc": args.mc, "seeds": args.seeds, "tours": tours}, indent=1)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
