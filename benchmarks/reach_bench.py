"""Reachability benchmark: the least energy from a depot to every cell (and back), against scipy's Dijkstra.

On seeded procedural maps (1 m cells, hills, four grounds, rocks, one wall) of 512^2 and
2048^2 cells (``--quick``: 256^2 and 512^2), with the depot at the free cell nearest the
centre, the script times

- ``moves``: costing the stride-1 lattice's directed moves (``lattice_move_energies``,
  the stride-1 kernel; cached on the cost afterwards), against the lattice planner's own
  kernel (``lattice_weights``) on the same cost: CPU-time ratio and the largest relative
  difference of the moves;
- ``one way`` and ``round trip``: :func:`planner.reachability` searches on the cached
  moves (the round trip runs its forward and reversed searches on two threads);
- ``cold round trip``: what one call costs on a fresh cost: moves + round-trip search —
  the issue's target (2048^2 in <= 3 s on a 2-core machine);
- the baseline in the same run: :func:`scipy.sparse.csgraph.dijkstra` from the same virtual
  depot node over the same graph as a CSR matrix (building the matrix is reported apart),
  forward and on the transposed graph; its answers are compared with ours (max relative
  difference over every cell, and whether the same cells are unreachable), and the speed
  ratio is scipy's search time over ours.

Each search is the best of ``--repeats`` runs; numba compilation is excluded (warm-up
first). Peak RSS of the process and the load average are reported: on a shared machine the
wall times include waiting for a core, and the cold call's CPU seconds (over all threads)
are the work done. Usage::

    python benchmarks/reach_bench.py --out bench_reach.json    # 512^2 and 2048^2 (about 2 minutes)
    python benchmarks/reach_bench.py --quick                    # 256^2 and 512^2 (seconds)
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import sys
import time
from pathlib import Path
from typing import Any

import numba
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from planner import EnergyCost, reachability, warm_up_kernels
from planner.cost_spec import CostSpec
from planner.kernels import lattice_weights
from planner.lattice import LATTICE_OFFSETS
from planner.reachability import depot_links, lattice_move_energies, warm_up_reachability
from terrain.procedural import procedural_map
from terrawatt_base.atomic import write_json_atomic

#: The issue's target: a cold round-trip reachability on 2048^2 cells within this many seconds.
TARGET_S = 3.0
TARGET_SIZE = 2048


def _best(fn: Any, repeats: int) -> tuple[float, Any]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _depot(cost: EnergyCost) -> tuple[float, float]:
    """The free cell centre nearest the map centre, in the largest connected free region."""
    labels = cost.components()
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    rr, cc = np.nonzero(labels == int(np.argmax(sizes)))
    rows, cols = cost.shape
    k = int(np.argmin((rr - rows / 2) ** 2 + (cc - cols / 2) ** 2))
    x, y = cost.terrain.xy(rr[k], cc[k])
    return float(x), float(y)


def _lattice_csr(w: np.ndarray, rows: int, cols: int) -> csr_matrix:
    """The lattice graph of dense move energies ``w`` as an (n, n) CSR matrix (absent moves not stored)."""
    n = rows * cols
    mask = np.isfinite(w)
    delta = LATTICE_OFFSETS[:, 0] * cols + LATTICE_OFFSETS[:, 1]
    targets = (np.arange(n, dtype=np.int64)[:, None] + delta[None, :])[mask].astype(np.int32)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(mask.sum(axis=1), out=indptr[1:])
    return csr_matrix((w[mask], targets, indptr), shape=(n, n))


def _with_source(g: csr_matrix, nodes: np.ndarray, costs: np.ndarray) -> csr_matrix:
    """``g`` plus a virtual node ``n`` with edges to ``nodes`` at ``costs``."""
    n = g.shape[0]
    ok = np.isfinite(costs)
    data = np.concatenate([g.data, costs[ok]])
    indices = np.concatenate([g.indices, nodes[ok].astype(g.indices.dtype)])
    indptr = np.append(g.indptr, g.indptr[-1] + ok.sum())
    return csr_matrix((data, indices, indptr), shape=(n + 1, n + 1))


def _compare(ours: np.ndarray, ref: np.ndarray) -> tuple[float, bool]:
    same_inf = bool(np.array_equal(np.isinf(ours), np.isinf(ref)))
    fin = np.isfinite(ours) & np.isfinite(ref)
    rel = np.abs(ours[fin] - ref[fin]) / np.maximum(np.abs(ref[fin]), 1e-300)
    return float(rel.max()) if rel.size else 0.0, same_inf


def _run_size(n: int, args: argparse.Namespace) -> dict[str, Any]:
    t0 = time.perf_counter()
    tmap = procedural_map((n, n), 1.0, seed=args.seed, n_walls=1)
    map_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    cost = CostSpec().build(tmap)
    prep_s = time.perf_counter() - t0
    depot = _depot(cost)
    # a cold call on a fresh cost: the moves, then the round-trip search (wall and CPU seconds)
    t0, c0 = time.perf_counter(), time.process_time()
    w, _ = lattice_move_energies(cost)
    t1, c1 = time.perf_counter(), time.process_time()
    reachability(cost, depot, round_trip=True)
    t2, c2 = time.perf_counter(), time.process_time()
    moves_s, moves_cpu_s, cold_s, cold_cpu_s = t1 - t0, c1 - c0, t2 - t0, c2 - c0
    one_s, one = _best(lambda: reachability(cost, depot), args.repeats)
    c0 = time.process_time()
    one_cpu_s = (reachability(cost, depot), time.process_time() - c0)[1]
    rt_s, rt = _best(lambda: reachability(cost, depot, round_trip=True), args.repeats)
    ours_rss_gib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # before any baseline
    # the lattice planner's own move kernel on the same cost: a baseline and a check of the moves
    arr = cost.arrays
    t0, c0 = time.perf_counter(), time.process_time()
    ref_w = lattice_weights(arr.cells, arr.grade_table, arr.geo, 1, 0, n, n, LATTICE_OFFSETS[:8])
    lat_moves_s, lat_moves_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    moves_err, moves_inf = _compare(w.ravel(), ref_w.ravel())
    del ref_w
    # scipy baseline on the same graph and the same depot links
    t0 = time.perf_counter()
    g = _lattice_csr(w, n, n)
    nodes, out_j, back_j = depot_links(cost, np.array(depot))
    fwd_graph = _with_source(g, nodes, out_j)
    back_graph = _with_source(g.T.tocsr(), nodes, back_j)
    csr_s = time.perf_counter() - t0
    sp_fwd_s, sp_fwd = _best(lambda: dijkstra(fwd_graph, directed=True, indices=n * n), args.repeats)
    sp_back_s, sp_back = _best(lambda: dijkstra(back_graph, directed=True, indices=n * n), args.repeats)
    err_f, inf_f = _compare(rt.forward_energy_j.ravel(), np.where(cost.blocked.ravel(), np.inf, sp_fwd[: n * n]))
    err_b, inf_b = _compare(rt.back_energy_j.ravel(), np.where(cost.blocked.ravel(), np.inf, sp_back[: n * n]))
    return {
        "cells": n * n,
        "size": n,
        "edges": int(g.nnz),
        "map_s": map_s,
        "prep_s": prep_s,
        "moves_s": moves_s,
        "moves_cpu_s": moves_cpu_s,
        "lattice_kernel_moves_s": lat_moves_s,
        "lattice_kernel_moves_cpu_s": lat_moves_cpu_s,
        "ratio_lattice_kernel_over_ours_moves_cpu": lat_moves_cpu_s / moves_cpu_s,
        "moves_max_rel_diff_vs_lattice_kernel": moves_err,
        "moves_same_absent_as_lattice_kernel": moves_inf,
        "one_way_search_s": one_s,
        "one_way_search_cpu_s": one_cpu_s,
        "round_trip_search_s": rt_s,
        "cold_round_trip_s": cold_s,
        "cold_round_trip_cpu_s": cold_cpu_s,
        "load_average_1min": os.getloadavg()[0],
        "scipy_csr_build_s": csr_s,
        "scipy_forward_s": sp_fwd_s,
        "scipy_round_trip_s": sp_fwd_s + sp_back_s,
        "ratio_scipy_over_ours_one_way": sp_fwd_s / one_s,
        "ratio_scipy_over_ours_round_trip": (sp_fwd_s + sp_back_s) / rt_s,
        "max_rel_diff_forward": err_f,
        "max_rel_diff_back": err_b,
        "same_unreachable_cells": inf_f and inf_b,
        "reachable_fraction": one.reachable_fraction,
        "peak_rss_ours_gib": ours_rss_gib,
        "peak_rss_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20,
    }


def _print(rows: list[dict[str, Any]], compile_s: float) -> None:
    print(f"numba threads {numba.get_num_threads()}, cpu count {os.cpu_count()}; warm-up (compile/load) "
          f"{compile_s:.1f} s, not in the times below\n")
    header = (f"{'cells':>9} {'prep s':>7} {'moves s':>8} {'x moves':>7} {'1-way s':>8} {'round s':>8} {'cold RT s':>9} {'CPU s':>6} "
              f"{'scipy 1w s':>10} {'scipy RT s':>10} {'x 1-way':>8} {'x RT':>6} {'max rel diff':>12} {'RSS GiB':>8}")
    print(header)
    print("-" * len(header))
    for r in rows:
        print(f"{r['size']:>5}^2   {r['prep_s']:>7.2f} {r['moves_s']:>8.2f} "
              f"{r['ratio_lattice_kernel_over_ours_moves_cpu']:>7.1f} {r['one_way_search_s']:>8.2f} "
              f"{r['round_trip_search_s']:>8.2f} {r['cold_round_trip_s']:>9.2f} {r['cold_round_trip_cpu_s']:>6.2f} "
              f"{r['scipy_forward_s']:>10.2f} "
              f"{r['scipy_round_trip_s']:>10.2f} {r['ratio_scipy_over_ours_one_way']:>8.1f} "
              f"{r['ratio_scipy_over_ours_round_trip']:>6.1f} "
              f"{max(r['max_rel_diff_forward'], r['max_rel_diff_back']):>12.1e} {r['peak_rss_ours_gib']:>8.2f}")
    print("\nx moves: CPU seconds of the lattice planner's move kernel (lattice_weights) over ours (same moves);")
    print("x: scipy's search time over ours (same graph, same depot); 'cold RT': moves + round-trip search "
          "(wall), 'CPU s' its CPU seconds over all threads; RSS: peak before the baselines ran")
    loads = ", ".join(f"{r['load_average_1min']:.1f}" for r in rows)
    print(f"load average (1 min) after each size: {loads} on {os.cpu_count()} cores")


def _targets(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for r in rows:
        if r["size"] == TARGET_SIZE:
            out.append({"target": f"cold round-trip reachability on {TARGET_SIZE}^2 <= {TARGET_S:g} s",
                        "measured_s": r["cold_round_trip_s"], "met": r["cold_round_trip_s"] <= TARGET_S})
    out.append({"target": "moves equal the lattice planner's (rel 1e-9, same absent moves)",
                "measured": max(r["moves_max_rel_diff_vs_lattice_kernel"] for r in rows),
                "met": all(r["moves_same_absent_as_lattice_kernel"] and r["moves_max_rel_diff_vs_lattice_kernel"] <= 1e-9
                           for r in rows)})
    out.append({"target": "same answers as scipy (rel 1e-9, same unreachable cells)",
                "measured": max(max(r["max_rel_diff_forward"], r["max_rel_diff_back"]) for r in rows),
                "met": all(r["same_unreachable_cells"] and max(r["max_rel_diff_forward"], r["max_rel_diff_back"]) <= 1e-9
                           for r in rows)})
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="256^2 and 512^2, one repeat")
    parser.add_argument("--sizes", type=int, nargs="+", default=None, metavar="N", help="map sides (cells)")
    parser.add_argument("--repeats", type=int, default=None, help="runs per timing, best kept (default 3; quick 1)")
    parser.add_argument("--seed", type=int, default=0, help="procedural map seed (default 0)")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    args = parser.parse_args(argv)
    sizes = args.sizes or ([256, 512] if args.quick else [512, TARGET_SIZE])
    if args.repeats is None:
        args.repeats = 1 if args.quick else 3
    compile_s = warm_up_kernels() + warm_up_reachability()
    rows = []
    for n in sizes:
        print(f"... {n}^2", file=sys.stderr, flush=True)
        rows.append(_run_size(n, args))
    _print(rows, compile_s)
    targets = _targets(rows)
    print()
    for t in targets:
        print(f"{'MET ' if t['met'] else 'MISS'} {t['target']}: {t.get('measured_s', t.get('measured'))!r}")
    if args.out is not None:
        write_json_atomic(args.out, {
            "machine": {"platform": platform.platform(), "python": platform.python_version(),
                        "cpu_count": os.cpu_count(), "numba_threads": numba.get_num_threads()},
            "compile_s": compile_s, "repeats": args.repeats, "seed": args.seed, "sizes": rows, "targets": targets,
        })
        print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
