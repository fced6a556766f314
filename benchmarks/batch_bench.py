"""Batch planning benchmark: routes/s in process vs a local dask cluster, and the lattice search vs networkx.

On a seeded procedural map (1 m cells), a fixed set of random (start, goal) pairs in one free
region is planned three ways, all in the same run:

- **in process**: :func:`planner.plan_batch` (lattice planner, refinement, the comparison with
  the shortest route: the full row of each pair), on a fresh copy of the cost so the lattice
  graph is built inside the timing, as each worker has to;
- **local cluster**: the same call on a ``LocalCluster`` of ``--workers`` processes of one
  thread (started and warmed up, numba kernels loaded, before the timing; both reported).
  The cost is sent once (``run_tasks``); each worker builds its lattice graph on its first pair.
  Scaling efficiency = cluster routes/s / (workers x in-process routes/s);
- **peer baseline**: the bare search on the same directed 16-connected lattice graph (same
  edges, same energy weights, from :meth:`planner.Lattice.graph`): the library's compiled A*
  (:meth:`planner.Lattice.shortest_path`) against ``networkx.single_source_dijkstra`` on a
  ``networkx.DiGraph`` of that graph, what a Python user would reach for. Both give the same
  minimum energy (checked; the baseline also tries the straight start-goal segment, as the
  library's query does); the ratio is search routes/s, graph building reported apart;
- **Monte Carlo**: :func:`planner.simulate_missions_mc` of the first pair's route, in process
  and on the same cluster: missions/s and the check that the percentiles are equal.

Rows are compared too: the cluster's rows must equal the in-process rows (planning times
aside). Ratios, not absolute seconds, are the result (the machine is shared: run it with
``nice``). Needs the ``distributed`` and ``bench`` extras (``pip install 'terrawatt[distributed,bench]'``,
or just ``pip install networkx``). Usage::

    python benchmarks/batch_bench.py --out bench_batch.json      # 256^2, 48 pairs (~2 min)
    python benchmarks/batch_bench.py --quick                       # 128^2, 16 pairs (~30 s)
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import math
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from planner import EnergyCost, Lattice, plan_batch, plan_route, simulate_missions_mc, warm_up_kernels
from planner.cache import CACHE_SIZE, ResultCache
from planner.cost_spec import CostSpec
from planner.missions import MonteCarloStudy
from terrain.procedural import procedural_map
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.dask_client import Compute


def _need(module: str, extra: str) -> Any:
    try:
        return __import__(module)
    except ImportError:
        sys.exit(f"batch_bench needs {module}: pip install 'terrawatt[{extra}]' (or pip install {module})")


def _fresh(cost: EnergyCost, *, keep_lattices: bool = False) -> EnergyCost:
    """The cost without its cached results (and lattice graphs, unless ``keep_lattices``): a worker's cold start.

    The per-query results are always dropped: a batch planned twice on one cost would
    otherwise find its comparisons cached.
    """
    c = copy.copy(cost)
    c.lattices = dict(cost.lattices) if keep_lattices else {}
    c.results = ResultCache(CACHE_SIZE)
    return c


def _pairs(cost: EnergyCost, n: int, rng: np.random.Generator, min_dist_m: float) -> np.ndarray:
    """``n`` pairs of free cell centres of the largest free region, at least ``min_dist_m`` apart."""
    labels = cost.components()
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    rr, cc = np.nonzero(labels == int(np.argmax(sizes)))
    x, y = cost.terrain.xy(rr, cc)
    pts = np.column_stack([x, y])
    out: list[list[float]] = []
    while len(out) < n:
        a, b = pts[rng.integers(len(pts), size=2)]
        if math.dist(a, b) >= min_dist_m:
            out.append([*a, *b])
    return np.array(out)


def _outcome(rows: Any) -> list[dict[str, Any]]:
    return [{k: v for k, v in dataclasses.asdict(r).items() if k != "planning_time_s"} for r in rows]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> bool:
    def eq(x: Any, y: Any) -> bool:
        return x == y or (isinstance(x, float) and isinstance(y, float) and math.isnan(x) and math.isnan(y))

    return all(eq(ra[k], rb[k]) for ra, rb in zip(a, b) for k in ra) and len(a) == len(b)


def _mc_rows(client: Any, cost: EnergyCost, pair: np.ndarray, n: int) -> dict[str, Any]:
    """Monte Carlo missions of one route: missions/s in process and on the cluster, the same percentiles."""
    route = plan_route(cost.terrain, pair[:2], pair[2:], cost=cost, planner="lattice")
    battery = Battery(2.0, 24.0)
    here = simulate_missions_mc(cost.terrain, route, battery, MonteCarloStudy(n, seed=0))
    there = simulate_missions_mc(cost.terrain, route, battery, MonteCarloStudy(n, seed=0, chunk_size=4),
                                 compute=Compute(client=client))
    return {
        "missions": n, "route_length_m": route.length_m, "in_process_s": here.elapsed_s, "cluster_s": there.elapsed_s,
        "in_process_missions_per_s": n / here.elapsed_s, "cluster_missions_per_s": n / there.elapsed_s,
        "speedup": here.elapsed_s / there.elapsed_s,
        "percentiles_equal": here.energy_percentiles_wh == there.energy_percentiles_wh
        and bool(np.array_equal(here.energy_j, there.energy_j)),
        "energy_wh": here.energy_percentiles_wh, "p_below_reserve": here.p_below_reserve,
    }


def _batch_rows(cost: EnergyCost, pairs: np.ndarray, workers: int, repeats: int,
                mc_n: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """In process and on a local cluster, ``repeats`` times each, alternating; the median routes/s of each;
    then ``mc_n`` Monte Carlo missions of the first pair's route, here and on the same cluster."""
    distributed = _need("distributed", "distributed")
    here_rps, warm_rps, there_rps, inflation, cpu_ratio, equal = [], [], [], [], [], True
    t0 = time.perf_counter()
    Lattice.for_cost(cost, 1)  # the lattice of the "lattice built" rows
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
        start_s = time.perf_counter() - t0
        t1 = time.perf_counter()
        client.run(warm_up_kernels)  # import terrawatt and load the compiled kernels on every worker
        warm_s = time.perf_counter() - t1
        for _ in range(repeats):
            cpu0 = time.process_time()
            here = plan_batch(_fresh(cost), pairs)
            cpu_here = time.process_time() - cpu0
            warm_here = plan_batch(_fresh(cost, keep_lattices=True), pairs)  # lattice built already
            cpu0 = client.run(time.process_time)
            there = plan_batch(cost, pairs, compute=Compute(client=client))  # sent afresh: workers start cold
            cpu_there = sum(t - cpu0[w] for w, t in client.run(time.process_time).items())
            cpu_ratio.append(cpu_there / cpu_here)
            here_rps.append(here.routes_per_s)
            warm_rps.append(warm_here.routes_per_s)
            there_rps.append(there.routes_per_s)
            # the same searches timed on the workers: ~1 on an idle machine, more when others take the cores
            inflation.append(float(np.sum(there.column("planning_time_s")) / np.sum(here.column("planning_time_s"))))
            equal = equal and _same(_outcome(here.rows), _outcome(there.rows))
        mc = _mc_rows(client, cost, pairs[0], mc_n)
    rps_here, rps_warm, rps_there = (float(np.median(v)) for v in (here_rps, warm_rps, there_rps))
    return {
        "pairs": len(pairs), "found": here.n_found, "errors": here.n_errors, "repeats": repeats,
        "in_process_s": len(pairs) / rps_here, "in_process_routes_per_s": rps_here,
        "in_process_routes_per_s_all": here_rps,
        "in_process_warm_routes_per_s": rps_warm,
        "workers": workers, "cluster_start_s": start_s, "worker_warmup_s": warm_s,
        "cluster_s": len(pairs) / rps_there, "cluster_routes_per_s": rps_there, "cluster_routes_per_s_all": there_rps,
        "speedup": rps_there / rps_here, "scaling_efficiency": rps_there / (workers * rps_here),
        "cluster_rows_equal_in_process": equal,
        "worker_time_inflation": float(np.median(inflation)),
        "worker_cpu_ratio": float(np.median(cpu_ratio)),
        "median_energy_saved_pct": here.median_saving_pct(),
    }, mc


def _peer_rows(cost: EnergyCost, pairs: np.ndarray) -> dict[str, Any]:
    nx = _need("networkx", "bench")
    t0 = time.perf_counter()
    lattice = Lattice(cost, 1)
    lattice_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    graph = nx.from_scipy_sparse_array(lattice.graph("energy"), create_using=nx.DiGraph, edge_attribute="weight")
    nx_build_s = time.perf_counter() - t0
    rows, cols = cost.terrain.rowcol(pairs[:, [0, 2]].ravel(), pairs[:, [1, 3]].ravel())
    nodes = (np.asarray(rows) * cost.shape[1] + np.asarray(cols)).reshape(-1, 2)
    ours, theirs = [], []
    t0 = time.perf_counter()
    for p in pairs:
        ours.append(lattice.shortest_path(p[:2], p[2:], weight="energy").objective)
    ours_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    for p, (s, g) in zip(pairs, nodes):
        try:
            best = nx.single_source_dijkstra(graph, int(s), int(g), weight="weight")[0]
        except nx.NetworkXNoPath:
            best = math.inf
        # the library's query also tries the straight start-goal segment (any heading): so does the baseline
        theirs.append(min(best, cost.segment_energy_one_j(p[0], p[1], p[2], p[3])))
    nx_s = time.perf_counter() - t0
    a, b = np.array(ours), np.array(theirs)
    finite = np.isfinite(a) & np.isfinite(b)
    rel = float(np.max(np.abs(a[finite] - b[finite]) / b[finite])) if finite.any() else math.nan
    n = len(pairs)
    return {
        "pairs": n, "nodes": lattice.n_nodes, "edges": lattice.n_edges,
        "lattice_build_s": lattice_s, "networkx_graph_build_s": nx_build_s,
        "lattice_search_routes_per_s": n / ours_s, "networkx_dijkstra_routes_per_s": n / nx_s,
        "search_speedup_vs_networkx": nx_s / ours_s,
        "max_rel_energy_difference": rel,
        "same_reachability": bool(np.array_equal(np.isfinite(a), np.isfinite(b))),
    }


def _print(batch: dict[str, Any], peer: dict[str, Any], size: int) -> None:
    print(f"\nbatch planning on a {size}^2 procedural map: {batch['pairs']} pairs "
          f"({batch['found']} found, median saving vs shortest {batch['median_energy_saved_pct']:.1f} %)")
    print(f"(median of {batch['repeats']} runs each)")
    print(f"{'where':<32} {'seconds':>8} {'routes/s':>9} {'vs in process':>14}")
    print("-" * 66)
    print(f"{'in process (cold cost)':<32} {batch['in_process_s']:>8.2f} {batch['in_process_routes_per_s']:>9.2f} "
          f"{1.0:>14.2f}")
    warm = batch["in_process_warm_routes_per_s"]
    print(f"{'in process (lattice built)':<32} {batch['pairs'] / warm:>8.2f} {warm:>9.2f} "
          f"{warm / batch['in_process_routes_per_s']:>14.2f}")
    label = f"local cluster, {batch['workers']} workers"
    print(f"{label:<32} {batch['cluster_s']:>8.2f} {batch['cluster_routes_per_s']:>9.2f} {batch['speedup']:>14.2f}")
    print(f"scaling efficiency {100 * batch['scaling_efficiency']:.0f} % (cluster start {batch['cluster_start_s']:.1f} s "
          f"and worker warm-up {batch['worker_warmup_s']:.1f} s not included); cluster rows equal in-process rows: "
          f"{batch['cluster_rows_equal_in_process']}")
    print(f"per-route planning time on the workers / in process: {batch['worker_time_inflation']:.2f} (wall); "
          f"CPU time of the workers / in process: {batch['worker_cpu_ratio']:.2f} (the same work costs the "
          "same CPU: a wall ratio above it is time the workers waited for a core)")
    print(f"\npeer baseline: minimum-energy search on the same directed 16-connected lattice "
          f"({peer['nodes']} nodes, {peer['edges']} edges), {peer['pairs']} pairs")
    print(f"{'search':<32} {'routes/s':>9} {'graph build s':>14}")
    print("-" * 57)
    print(f"{'terrawatt lattice A* (numba)':<32} {peer['lattice_search_routes_per_s']:>9.2f} "
          f"{peer['lattice_build_s']:>14.2f}")
    print(f"{'networkx single_source_dijkstra':<32} {peer['networkx_dijkstra_routes_per_s']:>9.2f} "
          f"{peer['networkx_graph_build_s']:>14.2f}")
    print(f"search speed-up vs networkx: {peer['search_speedup_vs_networkx']:.0f}x; "
          f"largest relative energy difference {peer['max_rel_energy_difference']:.1e}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256, help="map side in cells (default 256)")
    parser.add_argument("--pairs", type=int, default=48, help="pairs of the batch (default 48)")
    parser.add_argument("--peer-pairs", type=int, default=8, help="pairs of the networkx comparison (default 8)")
    parser.add_argument("--workers", type=int, default=2, help="local cluster worker processes (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="map and pair seed")
    parser.add_argument("--repeats", type=int, default=3, help="timed repetitions of each batch (median; default 3)")
    parser.add_argument("--mc", type=int, default=32, help="Monte Carlo missions of the first pair's route (default 32)")
    parser.add_argument("--quick", action="store_true", help="small run: 128^2, 16 pairs, 4 networkx pairs, 8 missions")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.pairs, args.peer_pairs, args.repeats, args.mc = 128, 16, 4, 1, 8
    _need("distributed", "distributed")
    _need("networkx", "bench")
    compile_s = warm_up_kernels()
    tmap = procedural_map((args.size, args.size), 1.0, seed=args.seed)
    t0 = time.perf_counter()
    cost = CostSpec().build(tmap)
    prep_s = time.perf_counter() - t0
    rng = np.random.default_rng(args.seed)
    pairs = _pairs(cost, args.pairs, rng, min_dist_m=args.size / 3)
    load_before = os.getloadavg()[0]
    batch, mc = _batch_rows(cost, pairs, args.workers, args.repeats, args.mc)
    peer = _peer_rows(cost, pairs[: args.peer_pairs])
    load = (load_before + os.getloadavg()[0]) / 2
    _print(batch, peer, args.size)
    print(f"\nMonte Carlo: {mc['missions']} missions of a {mc['route_length_m']:.0f} m route: "
          f"{mc['in_process_missions_per_s']:.1f} missions/s in process, {mc['cluster_missions_per_s']:.1f} on "
          f"{args.workers} workers ({mc['speedup']:.2f}x); the same percentiles: {mc['percentiles_equal']}")
    print(f"\n(1-minute load average during the run: about {load:.1f} on {os.cpu_count()} cores; "
          "other work on the machine shows in the ratios)")
    if args.out is not None:
        payload = {
            "benchmark": "batch_bench", "size": args.size, "seed": args.seed, "map_preparation_s": prep_s,
            "kernel_compile_s": compile_s, "batch": batch, "peer": peer, "monte_carlo": mc,
            "machine": {"python": platform.python_version(), "cpus": os.cpu_count(), "platform": platform.platform(),
                        "load_average_1min": load},
        }
        write_json_atomic(args.out, payload, indent=1)
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
