"""Map-size benchmark: peak memory (RSS) and time to prepare and plan from a GeoTIFF DEM, full resolution vs coarse-to-fine.

For each map side N (512, 2048, 4096; 8192 with ``--big``; 1 m cells) the script writes a
seeded synthetic DEM (closed-form hills, undulations and a ridge with two passes, so some cells are steeper
than the 20-degree slope limit) to a GeoTIFF in a temporary folder, tile by tile, and then
runs each measurement in a fresh child process (its peak RSS is ``getrusage`` of that child
alone; the numba kernels are loaded from their cache and warmed on a tiny map first, which
is excluded):

- ``windowed``: :func:`terrain.iter_surface_windows` (slope, aspect and gradients tile by tile
  with halo cells, kept as the blocked mask a cost needs) — preparation that never holds
  the whole raster;
- ``full``: ``read_geotiff`` + ``CostSpec().build`` (prepare), then the directed
  16-connected 1-cell lattice optimum (graph build + A*; the baseline, the exact optimum);
- ``c2f``: the same preparation, then :func:`planner.plan_coarse_to_fine` (factor side / 256
  within 4..16 by default, a coarse lattice of about 256^2 nodes; the corridor is three
  coarse cells);
- ``wc2f`` (windowed c2f): :func:`planner.plan_coarse_to_fine` on the same file (its path) — the
  coarse map tile by tile, the full resolution only in the corridor's window, never the
  whole raster; its route is compared with ``c2f``'s (equal where both run).

- ``chain2`` / ``chain8`` (up to 4096^2): ``wc2f`` with a fine-window budget of (N/2)^2 / (N/8)^2
  cells, so the fine stage runs in chained windows along the route; its energy is compared
  with the full-resolution optimum like ``c2f``'s.

With ``--huge`` a 16384^2 DEM (1 GiB of float32, written tile by tile and deleted) runs in
``wc2f`` only, on a shorter route (``BIG_START_FRAC`` -> ``BIG_GOAL_FRAC``), as it did before
the fine stage could chain windows (its figures stay comparable).

``--sizes 32768`` (or any side >= ``COG_MIN``) writes the DEM as a cloud-optimised GeoTIFF
layout (512^2 internal tiles, zstd, floating-point predictor; 4 GiB of float32 in about
1 GiB of file, in the temporary folder, deleted after) and runs ``wc2f`` corner to corner
(its bounding window would be ~10^9 cells: the fine stage chains windows) and ``tiles``:
per 1024^2 tile, seconds (wall and CPU) and bytes (file, peak RSS) to read, to reduce to
coarse cells (the coarse stage's work per tile), to price a full EnergyCost, and to build the
tile's border graph (Dijkstra from portals on the tile's border over its coarse lattice) —
the figures the plan for a continent (10^10 cells, tiles as dask tasks) is computed from.
Each child records the load average before and after it (the machine is shared).

Choosing the start and goal (free cells near fixed map fractions, found in 129^2 windows
in the parent process, so every mode plans between the same points) is the benchmark's own
work and is not timed.

It prints a table and writes JSON (``--out``): per size, wall time (and CPU time, less
sensitive to a shared machine's load) and peak RSS of each child,
and the coarse-to-fine route's energy over the full-resolution optimum and its time over
the full-resolution time (ratios measured in the same run). The full-resolution lattice is
not run above 4096^2 (its graph alone needs 16 edges x 8 bytes per cell, about 9 GB at
8192^2): there, only coarse-to-fine runs. Targets (2-core machine): 2048^2 prepares and
plans in <= 5 s and <= 4 GiB; 8192^2 from a GeoTIFF in <= 60 s and <= 8 GiB; coarse-to-fine
within 1 % of the optimum on 4096^2 (chained windows too); 32768^2 from a COG in <= 120 s and
<= 6 GiB.

Usage::

    python benchmarks/map_scale_bench.py --out bench_map_scale.json   # 512, 2048, 4096 (~5 min)
    python benchmarks/map_scale_bench.py --big                        # adds 8192 (coarse-to-fine only)
    python benchmarks/map_scale_bench.py --quick                      # 256 and 512 (~30 s)
    python benchmarks/map_scale_bench.py --sizes 8192 --huge          # 8192 (all but full) and 16384 (wc2f)
    python benchmarks/map_scale_bench.py --sizes 4096 32768           # chained windows checked; 32768^2 COG
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from planner.cost_spec import CostSpec

#: Start and goal as fractions of the map side.
START_FRAC, GOAL_FRAC = (0.08, 0.10), (0.92, 0.86)
#: Start and goal of the sizes only the windowed planner runs on (above ``C2F_MAX``).
BIG_START_FRAC, BIG_GOAL_FRAC = (0.08, 0.10), (0.40, 0.30)
#: Largest side the whole-map coarse-to-fine runs on.
C2F_MAX = 8192
#: Largest side the full-resolution lattice runs on.
FULL_MAX = 4096
#: Smallest side written as a compressed, tiled COG and planned corner to corner by ``wc2f`` alone.
COG_MIN = 32768
#: Fine-window budgets of the chained modes, as divisors of the map side.
CHAIN_MODES = {"chain2": 2, "chain8": 8}
#: Tile side (cells) of the per-tile figures, tiles sampled, portals every this many coarse border cells.
TILE, TILE_SAMPLES, PORTAL_EVERY = 1024, 24, 4
#: The continent of the plan: cells, and the wall times its tile pass is sized for.
CONTINENT_CELLS, CONTINENT_TARGETS_S = 1e10, (120.0, 600.0)
TARGETS = {"prep_plan_2048_s": 5.0, "prep_plan_2048_gib": 4.0, "c2f_8192_s": 60.0, "c2f_8192_gib": 8.0,
           "ratio_4096": 1.01, "wc2f_32768_s": 120.0, "wc2f_32768_gib": 6.0}


# ------------------------------------------------------------------ the synthetic DEM
def _hills(seed: int) -> np.ndarray:
    """Seeded hills as rows of (x, y, sigma) in map fractions and height / sigma (dimensionless)."""
    rng = np.random.default_rng(seed)
    n = 40
    return np.column_stack([rng.uniform(0, 1, n), rng.uniform(0, 1, n), rng.uniform(0.01, 0.05, n),
                            rng.uniform(0.15, 0.45, n) * rng.choice([-1, 1], n)])


def _elevation(x: np.ndarray, y: np.ndarray, side_m: float, hills: np.ndarray) -> np.ndarray:
    """Closed-form elevation (m) on the grid of x (columns, m) and y (rows, m): hills whose flanks reach ~10-30
    degrees, undulations, a ridge.

    Gaussians and undulations are separable, so each is an outer product of two 1-D factors
    (one exp per row and per column, not per cell): 4x faster than exp per cell, equal to it
    within 1e-13 m (the same float32 DEM)."""
    u, v = x / side_m, y / side_m
    z = np.outer(np.cos(2 * np.pi * 5 * v), 2.0 * np.sin(2 * np.pi * 7 * u) * side_m / 2048)
    for hx, hy, s, h in hills:
        z += np.outer(np.exp(-((v - hy) ** 2) / (2 * s * s)), h * s * side_m * np.exp(-((u - hx) ** 2) / (2 * s * s)))
    # a ridge across the diagonal (flanks ~40 degrees), with two passes through it
    ridge = np.exp(-((u[None, :] + v[:, None] - 1.0) ** 2) / (2 * 0.01**2))
    for px, py in ((0.3, 0.7), (0.65, 0.35)):
        ridge *= 1.0 - np.outer(np.exp(-((v - py) ** 2) / (2 * 0.04**2)), np.exp(-((u - px) ** 2) / (2 * 0.04**2)))
    return z + 0.012 * side_m * ridge


def write_dem(path: Path, n: int, seed: int, tile: int = 1024, *, compress: bool = False) -> float:
    """Write the n x n DEM (1 m cells, EPSG:32633) tile by tile; return the seconds spent.

    ``compress``: the layout of a cloud-optimised GeoTIFF (512^2 internal tiles, zstd with
    the floating-point predictor; no overviews, which the planner does not read) instead of
    uncompressed 256^2 tiles."""
    import rasterio

    t0 = time.perf_counter()
    hills = _hills(seed)
    profile = {"driver": "GTiff", "height": n, "width": n, "count": 1, "dtype": "float32", "crs": "EPSG:32633",
               "transform": rasterio.Affine(1.0, 0.0, 500_000.0, 0.0, -1.0, 4_990_000.0 + n), "tiled": True,
               "blockxsize": 256, "blockysize": 256}
    if compress:
        profile.update(blockxsize=512, blockysize=512, compress="zstd", predictor=3, bigtiff="if_safer")
    with rasterio.open(path, "w", **profile) as dst:
        for r0 in range(0, n, tile):
            for c0 in range(0, n, tile):
                rows, cols = min(tile, n - r0), min(tile, n - c0)
                y = n - (r0 + np.arange(rows) + 0.5)  # file row 0 is the northern edge
                x = c0 + np.arange(cols) + 0.5
                z = _elevation(x, y, float(n), hills)
                dst.write(z.astype(np.float32), 1, window=rasterio.windows.Window(c0, r0, cols, rows))
        dst.units = ("m",)
    return time.perf_counter() - t0


# ------------------------------------------------------------------ child processes
def _shape(tif: Path) -> tuple[int, int]:
    import rasterio

    with rasterio.open(tif) as src:
        return src.height, src.width


def _rss_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB on Linux


def _status_kib(field: str) -> int | None:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def _reset_peak() -> int | None:
    """Reset this process's peak RSS (Linux ``clear_refs`` 5); the current RSS (KiB), None where not possible."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        return None
    return _status_kib("VmRSS")


def _peak_over(base_kib: int | None) -> int | None:
    """Bytes of peak RSS above ``base_kib`` since the last reset."""
    peak = _status_kib("VmHWM")
    return None if base_kib is None or peak is None else max(0, peak - base_kib) * 1024


def free_point(tif: Path, frac: tuple[float, float], win: int = 64) -> tuple[float, float]:
    """The free cell centre nearest to a fractional position, in the largest free region of a 129^2 window."""
    from terrain import DemWindows

    with DemWindows(tif) as dem:
        rows, cols = dem.shape
        r0, c0 = int(frac[1] * (rows - 1)), int(frac[0] * (cols - 1))
        w = dem.read(slice(r0 - win if r0 >= win else 0, r0 + win + 1), slice(max(0, c0 - win), c0 + win + 1), halo=1)
        cost = CostSpec().build(w.terrain_map())
    labels = cost.components()
    big = np.argmax(np.bincount(labels.ravel())[1:]) + 1
    rr, cc = np.nonzero(labels == big)
    hr, hc = w.halo_rows.start, w.halo_cols.start
    k = int(np.argmin((rr + hr - r0) ** 2 + (cc + hc - c0) ** 2))
    x, y = cost.terrain.xy(rr[k], cc[k])
    return float(x), float(y)


def _warm() -> float:
    """Load (or compile) every kernel the children use, on a tiny map; seconds spent."""
    from planner import CoarseOptions, Lattice, plan_coarse_to_fine, warm_up_kernels
    from terrain import procedural_map, write_geotiff

    t0 = time.perf_counter()
    warm_up_kernels()
    tmap = procedural_map((48, 48), 1.0, seed=0, obstacle_fraction=0.0)
    cost = CostSpec().build(tmap)
    plan_coarse_to_fine(cost, (4.5, 4.5), (40.5, 40.5), CoarseOptions(factor=4))
    with tempfile.TemporaryDirectory() as folder:
        plan_coarse_to_fine(write_geotiff(tmap, Path(folder) / "warm.tif"), (4.5, 4.5), (40.5, 40.5),
                            CoarseOptions(factor=4))
    Lattice(cost, 1).shortest_path((4.5, 4.5), (40.5, 40.5))
    return time.perf_counter() - t0


def _route_digest(waypoints: np.ndarray) -> str:
    import hashlib

    return hashlib.sha1(np.ascontiguousarray(waypoints, dtype=np.float64).tobytes()).hexdigest()[:16]


def tile_figures(tif: Path, factor: int, samples: int = TILE_SAMPLES) -> dict[str, Any]:
    """Seconds (wall, CPU) and bytes per TILE^2 tile, over ``samples`` tiles spread over the map.

    Per tile: ``read`` (window with its halo: decompress, float64); ``coarse`` (slope, blocked
    cells and the block reductions to coarse cells: the coarse stage's work per tile);
    ``price`` (a full EnergyCost of the tile: what a fine window costs per cell); ``border``
    (the tile's coarse map from those coarse cells, its lattice and a Dijkstra from every
    PORTAL_EVERY-th coarse border cell over it: the tile's part of a coarse graph over tile
    borders). Bytes: the file's share per tile, the peak RSS above the baseline during read +
    coarse and during price (Linux ``clear_refs``), the border graph's arrays."""
    from scipy.sparse import csgraph

    from planner import Lattice
    from planner.coarse import coarse_cost, coarse_layers
    from terrain import DemWindows
    from terrain.surface import surface_layers

    limit = np.radians(20.0)
    per: dict[str, list[float]] = {k: [] for k in ("read_s", "read_cpu_s", "coarse_s", "coarse_cpu_s", "price_s",
                                                   "price_cpu_s", "border_s", "border_cpu_s", "portals",
                                                   "border_edges", "read_coarse_peak_b", "price_peak_b",
                                                   "border_b")}
    with DemWindows(tif) as dem:
        rows, cols = dem.shape
        across = -(-cols // TILE)
        n_tiles = -(-rows // TILE) * across
        for t in np.unique(np.linspace(0, n_tiles - 1, min(samples, n_tiles)).round().astype(int)).tolist():
            r0, c0 = (t // across) * TILE, (t % across) * TILE
            clock: list[tuple[float, float]] = []  # (wall, CPU) between the steps
            base = _reset_peak()
            clock.append((time.perf_counter(), time.process_time()))
            win = dem.read(slice(r0, r0 + TILE), slice(c0, c0 + TILE), halo=1)
            clock.append((time.perf_counter(), time.process_time()))
            blocked = surface_layers(win.elevation_m, win.cell_size_m)["slope"][win.crop] > limit
            layers = coarse_layers(win.elevation_m[win.crop], blocked, np.zeros(blocked.shape, np.int32), factor)
            clock.append((time.perf_counter(), time.process_time()))
            per["read_coarse_peak_b"].append(_peak_over(base))
            del blocked
            base = _reset_peak()
            clock.append((time.perf_counter(), time.process_time()))
            cost = CostSpec().build(win.terrain_map())
            clock.append((time.perf_counter(), time.process_time()))
            per["price_peak_b"].append(_peak_over(base))
            clock.append((time.perf_counter(), time.process_time()))
            corner = (win.origin_xy_m[0] + (win.cols.start - win.halo_cols.start) * win.cell_size_m,
                      win.origin_xy_m[1] + (win.rows.start - win.halo_rows.start) * win.cell_size_m)
            coarse = coarse_cost(cost, *layers, win.cell_size_m * factor, corner, win.crs)
            del cost, win
            graph = Lattice(coarse, 1).graph()
            ring = np.zeros(coarse.shape, dtype=bool)
            ring[[0, -1], ::PORTAL_EVERY] = ring[::PORTAL_EVERY, [0, -1]] = True
            portals = np.flatnonzero(ring & ~coarse.blocked)
            dist = csgraph.dijkstra(graph, indices=portals)
            joined = np.isfinite(dist[:, portals]).sum() - portals.size
            clock.append((time.perf_counter(), time.process_time()))
            # small arrays (the heap reuses freed memory, RSS does not show them): their bytes
            per["border_b"].append(float(sum(a.nbytes for a in (graph.data, graph.indices, graph.indptr, dist))))
            for i, step in ((1, "read"), (2, "coarse"), (4, "price"), (6, "border")):
                per[f"{step}_s"].append(clock[i][0] - clock[i - 1][0])
                per[f"{step}_cpu_s"].append(clock[i][1] - clock[i - 1][1])
            per["portals"].append(float(portals.size))
            per["border_edges"].append(float(joined))
            del coarse, graph, dist
    file_b = tif.stat().st_size
    out: dict[str, Any] = {"tile": TILE, "tiles_in_map": n_tiles, "tiles_sampled": len(per["read_s"]),
                           "factor": factor, "portal_every": PORTAL_EVERY,
                           "file_bytes": file_b, "file_bytes_per_tile": file_b / n_tiles,
                           "raw_float32_bytes_per_tile": 4 * TILE * TILE}
    for key, values in per.items():
        vals = [v for v in values if v is not None]
        out[key] = float(np.median(vals)) if vals else None
    # CPU s per tile of the coarse stage (read + coarse cells) and of a coarse-graph task (+ border graph)
    out["coarse_task_cpu_s"] = out["read_cpu_s"] + out["coarse_cpu_s"]
    out["border_task_cpu_s"] = out["coarse_task_cpu_s"] + out["border_cpu_s"]
    return out


def child(mode: str, tif: Path, factor: int, start: tuple[float, float], goal: tuple[float, float],
          budget: int | None = None) -> dict[str, Any]:
    """One measurement in this (fresh) process."""
    warm_s = _warm()
    base_gib = _rss_gib()
    from planner import CoarseOptions, Lattice, plan_coarse_to_fine
    from terrain import iter_surface_windows, read_geotiff

    out: dict[str, Any] = {"mode": mode, "warm_s": warm_s, "base_rss_gib": base_gib}
    t0, cpu0 = time.perf_counter(), time.process_time()
    if mode == "tiles":
        out.update(tile_figures(tif, factor))
        out["total_s"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - cpu0
        out["peak_rss_gib"] = _rss_gib()
        return out
    if mode == "windowed":
        # slope tile by tile (halo cells), kept only as the blocked mask a cost needs: memory is one tile
        blocked = np.zeros(_shape(tif), dtype=bool)
        limit = np.radians(20.0)
        for win in iter_surface_windows(tif, window_cells=1024):
            blocked[win.rows, win.cols] = win.layers["slope"] > limit
        out["prepare_s"] = time.perf_counter() - t0
        out["total_s"], out["cpu_s"] = out["prepare_s"], time.process_time() - cpu0
        out["blocked_pct"] = 100.0 * float(blocked.mean())
        out["peak_rss_gib"] = _rss_gib()
        return out
    if mode == "wc2f" or mode in CHAIN_MODES:
        plan = plan_coarse_to_fine(tif, start, goal, CoarseOptions(factor=factor, fine_window_budget_cells=budget))
        out["prepare_s"], out["plan_s"] = 0.0, time.perf_counter() - t0
        out["total_s"], out["cpu_s"] = out["plan_s"], time.process_time() - cpu0
        out["objective_j"] = plan.objective_j if plan.route.found else None
        out["energy_j"] = plan.route.energy_j if plan.route.found else None
        out["route"] = _route_digest(plan.route.waypoints_m)
        out["corridor_cells"], out["fallback"] = plan.corridor_cells, plan.fallback
        out["coarse_s"], out["fine_s"] = plan.coarse_time_s, plan.fine_time_s
        out["fine_window_cells"] = plan.fine_window_cells
        out["fine_windows"] = len(plan.fine_windows)
        out["fine_window_max_cells"] = plan.summary()["fine_window_max_cells"]
        out["budget_cells"] = budget
        out["length_m"] = plan.route.length_m if plan.route.found else None
        out["peak_rss_gib"] = _rss_gib()
        return out
    tmap = read_geotiff(tif)
    cost = CostSpec().build(tmap)
    out["prepare_s"] = time.perf_counter() - t0
    cpu_prep = time.process_time() - cpu0
    t1, cpu1 = time.perf_counter(), time.process_time()
    if mode == "full":
        lattice = Lattice(cost, 1)
        out["graph_s"] = time.perf_counter() - t1
        path = lattice.shortest_path(start, goal)
        out["objective_j"] = path.objective if path.found else None
        out["blocked_pct"] = 100.0 * float(cost.blocked.mean())
    else:
        plan = plan_coarse_to_fine(cost, start, goal, CoarseOptions(factor=factor))
        out["objective_j"] = plan.objective_j if plan.route.found else None
        out["route"] = _route_digest(plan.route.waypoints_m)
        out["corridor_cells"] = plan.corridor_cells
        out["fallback"] = plan.fallback
        out["coarse_s"], out["fine_s"] = plan.coarse_time_s, plan.fine_time_s
    out["plan_s"] = time.perf_counter() - t1
    out["total_s"] = out["prepare_s"] + out["plan_s"]
    out["cpu_s"] = cpu_prep + time.process_time() - cpu1
    out["peak_rss_gib"] = _rss_gib()
    return out


def _run_child(mode: str, tif: Path, factor: int, start: tuple[float, float], goal: tuple[float, float],
               budget: int | None = None) -> dict[str, Any]:
    cmd = [sys.executable, __file__, "--child", mode, "--tif", str(tif), "--factor", str(factor),
           "--start", *map(repr, start), "--goal", *map(repr, goal)] + (["--budget", str(budget)] if budget else [])
    load_before = os.getloadavg()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    load = {"load_before": load_before, "load_after": os.getloadavg()}
    if proc.returncode != 0:
        return {"mode": mode, "error": (proc.stderr.strip().splitlines() or ["?"])[-1], "returncode": proc.returncode,
                **load}
    return {**json.loads(proc.stdout.strip().splitlines()[-1]), **load}


# ------------------------------------------------------------------ the run
def auto_factor(n: int) -> int:
    """The default downsampling factor: a coarse lattice of about 256^2 nodes, factor within 4..16."""
    return min(16, max(4, n // 256))


def run(sizes: list[int], factor: int | None, seed: int) -> list[dict[str, Any]]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for n in sizes:
            tif = Path(folder) / f"dem_{n}.tif"
            write_s = write_dem(tif, n, seed, compress=n >= COG_MIN)
            f = auto_factor(n) if factor is None else factor
            fracs = (START_FRAC, GOAL_FRAC) if n <= C2F_MAX or n >= COG_MIN else (BIG_START_FRAC, BIG_GOAL_FRAC)
            start, goal = free_point(tif, fracs[0]), free_point(tif, fracs[1])
            row: dict[str, Any] = {"size": n, "cells": n * n, "factor": f, "write_geotiff_s": write_s,
                                   "file_bytes": tif.stat().st_size, "compressed": n >= COG_MIN,
                                   "start_xy_m": start, "goal_xy_m": goal, "route_fracs": fracs}
            modes = (["windowed", "c2f", "wc2f"] if n <= C2F_MAX else ["wc2f"]) + (["full"] if n <= FULL_MAX else [])
            modes += list(CHAIN_MODES) if n <= FULL_MAX else []
            modes += ["tiles"] if n >= COG_MIN else []
            for mode in modes:
                budget = (n // CHAIN_MODES[mode]) ** 2 if mode in CHAIN_MODES else None
                row[mode] = _run_child(mode, tif, f, start, goal, budget)
                print(f"  {n}^2 {mode}: {row[mode]}", file=sys.stderr, flush=True)
            full, c2f, wc2f = row.get("full", {}), row.get("c2f", {}), row["wc2f"]
            if full.get("objective_j") and c2f.get("objective_j"):
                row["energy_ratio"] = c2f["objective_j"] / full["objective_j"]
                row["time_ratio_full_over_c2f"] = full["total_s"] / c2f["total_s"]
            for mode in CHAIN_MODES:
                if full.get("objective_j") and row.get(mode, {}).get("objective_j"):
                    row[f"energy_ratio_{mode}"] = row[mode]["objective_j"] / full["objective_j"]
                    if wc2f.get("objective_j"):
                        row[f"energy_ratio_{mode}_over_wc2f"] = row[mode]["objective_j"] / wc2f["objective_j"]
            if "peak_rss_gib" in c2f and "peak_rss_gib" in wc2f:
                row["rss_ratio_wc2f_over_c2f"] = wc2f["peak_rss_gib"] / c2f["peak_rss_gib"]
                row["time_ratio_wc2f_over_c2f"] = wc2f["total_s"] / c2f["total_s"]
                row["routes_equal"] = (wc2f.get("route") == c2f.get("route")
                                       and wc2f.get("objective_j") == c2f.get("objective_j"))
            tif.unlink()
            rows.append(row)
    return rows


def _fmt(v: Any, spec: str) -> str:
    return format(v, spec) if isinstance(v, (int, float)) else f"{'-':>{spec.split('.')[0] or 1}}"


def print_table(rows: list[dict[str, Any]]) -> None:
    head = (f"{'side':>6} {'Mcells':>7} {'f':>3} | {'window s':>8} {'GiB':>5} | {'c2f prep':>8} {'plan':>6} {'total':>6} "
            f"{'GiB':>5} | {'full prep':>9} {'graph':>6} {'total':>6} {'GiB':>5} | {'E c2f/full':>10} "
            f"{'t full/c2f':>10}")
    print(head)
    print("-" * len(head))
    for r in rows:
        w, c, f = r.get("windowed", {}), r.get("c2f", {}), r.get("full", {})
        print(f"{r['size']:>6} {r['cells'] / 1e6:>7.1f} {r['factor']:>3} | {_fmt(w.get('total_s'), '8.2f')} "
              f"{_fmt(w.get('peak_rss_gib'), '5.2f')} | {_fmt(c.get('prepare_s'), '8.2f')} "
              f"{_fmt(c.get('plan_s'), '6.2f')} {_fmt(c.get('total_s'), '6.2f')} {_fmt(c.get('peak_rss_gib'), '5.2f')} | "
              f"{_fmt(f.get('prepare_s'), '9.2f')} {_fmt(f.get('graph_s'), '6.2f')} {_fmt(f.get('total_s'), '6.2f')} "
              f"{_fmt(f.get('peak_rss_gib'), '5.2f')} | {_fmt(r.get('energy_ratio'), '10.5f')} "
              f"{_fmt(r.get('time_ratio_full_over_c2f'), '10.1f')}")
        for mode in ("windowed", "c2f", "wc2f", "full", *CHAIN_MODES, "tiles"):
            if "error" in r.get(mode, {}):
                print(f"       {mode} failed: {r[mode]['error']}")
    print()
    head = (f"{'side':>6} {'f':>3} | {'wc2f s':>7} {'CPU s':>7} {'coarse':>7} {'fine':>6} {'GiB':>5} {'fine Mcells':>11} | "
            f"{'c2f s':>6} {'CPU s':>7} {'GiB':>5} | {'GiB w/c2f':>9} {'t w/c2f':>7} {'equal':>5}")
    print(head)
    print("-" * len(head))
    for r in rows:
        w, c = r["wc2f"], r.get("c2f", {})
        cells = w.get("fine_window_cells")
        print(f"{r['size']:>6} {r['factor']:>3} | {_fmt(w.get('total_s'), '7.2f')} {_fmt(w.get('cpu_s'), '7.2f')} "
              f"{_fmt(w.get('coarse_s'), '7.2f')} {_fmt(w.get('fine_s'), '6.2f')} {_fmt(w.get('peak_rss_gib'), '5.2f')} "
              f"{_fmt(cells / 1e6 if cells else None, '11.1f')} | {_fmt(c.get('total_s'), '6.2f')} "
              f"{_fmt(c.get('cpu_s'), '7.2f')} {_fmt(c.get('peak_rss_gib'), '5.2f')} | "
              f"{_fmt(r.get('rss_ratio_wc2f_over_c2f'), '9.2f')} {_fmt(r.get('time_ratio_wc2f_over_c2f'), '7.2f')} "
              f"{str(r.get('routes_equal', '-')):>5}")


def print_chained(rows: list[dict[str, Any]]) -> None:
    """Chained fine windows: each budget's windows, time and energy against the full-resolution optimum."""
    lines = []
    for r in rows:
        for mode in ("wc2f", *CHAIN_MODES):
            m = r.get(mode, {})
            if "fine_windows" not in m:
                continue
            lines.append(f"{r['size']:>6} {mode:>6} {_fmt(m.get('budget_cells') or None, '12.0f')} "
                         f"{m['fine_windows']:>7d} {m['fine_window_max_cells'] / 1e6:>9.2f} "
                         f"{m['fine_window_cells'] / 1e6:>9.1f} | {_fmt(m.get('total_s'), '7.2f')} "
                         f"{_fmt(m.get('cpu_s'), '7.2f')} {_fmt(m.get('coarse_s'), '7.2f')} {_fmt(m.get('fine_s'), '6.2f')} "
                         f"{_fmt(m.get('peak_rss_gib'), '5.2f')} | "
                         f"{_fmt(r.get(f'energy_ratio_{mode}', r.get('energy_ratio') if mode == 'wc2f' and r.get('routes_equal') else None), '10.5f')} "
                         f"{_fmt(m.get('load_before', [None])[0], '5.1f')}")
    if not lines:
        return
    head = (f"{'side':>6} {'mode':>6} {'budget':>12} {'windows':>7} {'max Mcell':>9} {'Mcells':>9} | {'wall s':>7} "
            f"{'CPU s':>7} {'coarse':>7} {'fine':>6} {'GiB':>5} | {'E / full':>10} {'load':>5}")
    print()
    print(head)
    print("-" * len(head))
    print("\n".join(lines))


def continent_plan(tiles: dict[str, Any], wc2f: dict[str, Any], size: int) -> dict[str, Any]:
    """The plan for a 10^10-cell DEM from the measured per-tile figures (tiles as dask tasks, a coarse graph
    over tile borders, the fine stage in chained windows), in numbers."""
    n_tiles = math.ceil(CONTINENT_CELLS / TILE**2)
    side = math.sqrt(CONTINENT_CELLS)
    task_cpu = tiles["border_task_cpu_s"]
    out: dict[str, Any] = {"cells": CONTINENT_CELLS, "tiles": n_tiles, "task_cpu_s": task_cpu,
                           "tile_pass_cpu_s": n_tiles * task_cpu,
                           "file_bytes": n_tiles * tiles["file_bytes_per_tile"],
                           "task_peak_bytes": (tiles["read_coarse_peak_b"] or 0) + tiles["border_b"]}
    # the coarse graph over tile borders: portals shared by two tiles, all pairs of a tile's portals joined
    out["graph_nodes"] = n_tiles * tiles["portals"] / 2
    out["graph_edges"] = n_tiles * tiles["border_edges"]
    out["graph_bytes"] = out["graph_edges"] * 12 + out["graph_nodes"] * 8  # CSR: int32 index + float64 weight
    for target in CONTINENT_TARGETS_S:
        out[f"workers_for_{int(target)}_s"] = math.ceil(n_tiles * task_cpu / target)
    # the fine stage: chained windows along a diagonal route, as measured on the side x side map
    if wc2f.get("fine_windows") and wc2f.get("length_m"):
        route_cells = wc2f["length_m"]  # 1 m cells
        out["fine_windows_per_1000_cells"] = 1000.0 * wc2f["fine_windows"] / route_cells
        out["fine_s_per_window"] = wc2f["fine_s"] / wc2f["fine_windows"]
        diag = route_cells / size * side  # the same route across the continent's side
        out["continent_route_cells"] = diag
        out["continent_fine_s"] = diag / 1000.0 * out["fine_windows_per_1000_cells"] * out["fine_s_per_window"]
    return out


def print_tiles(rows: list[dict[str, Any]]) -> None:
    for r in rows:
        t = r.get("tiles", {})
        if "read_s" not in t:
            continue
        mib = 2.0**20
        print(f"\nper {t['tile']}^2 tile of the {r['size']}^2 COG ({t['tiles_sampled']} of {t['tiles_in_map']} tiles, "
              f"median; wall s / CPU s / peak RSS over baseline, read + coarse cells together; border graph: its arrays):")
        print(f"  file         {t['file_bytes_per_tile'] / mib:7.2f} MiB (float32 {t['raw_float32_bytes_per_tile'] / mib:.0f} MiB)")
        for key, label in (("read", "read"), ("coarse", "coarse cells"), ("price", "EnergyCost"),
                           ("border", "border graph")):
            peak = t.get({"read": "read_coarse_peak_b", "coarse": "read_coarse_peak_b", "price": "price_peak_b",
                          "border": "border_b"}[key])
            print(f"  {label:<12} {t[key + '_s']:7.3f} / {t[key + '_cpu_s']:7.3f} s"
                  + (f"   peak {peak / mib:7.1f} MiB" if peak is not None and key != "read" else ""))
        print(f"  border graph: {t['portals']:.0f} portals (every {t['portal_every']}th coarse border cell), "
              f"{t['border_edges']:.0f} portal pairs joined")
        c = r.get("continent")
        if c:
            print(f"continent ({c['cells']:.0e} cells = {c['tiles']} tiles): {c['tile_pass_cpu_s'] / 3600:.2f} CPU h of "
                  f"tile tasks ({c['task_cpu_s']:.3f} s each), {c['file_bytes'] / 2**30:.0f} GiB of COG; workers for the "
                  f"tile pass in 120 s: {c['workers_for_120_s']}, in 10 min: {c['workers_for_600_s']} (a task holds "
                  f"{c['task_peak_bytes'] / 2**20:.0f} MiB); coarse graph "
                  f"{c['graph_nodes'] / 1e6:.2f} M portals, {c['graph_edges'] / 1e6:.0f} M edges "
                  f"({c['graph_bytes'] / 2**30:.2f} GiB)"
                  + (f"; fine stage {c['continent_fine_s']:.0f} s along a corner-to-corner route"
                     if "continent_fine_s" in c else ""))


def check_targets(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The issue's targets against this run (None when the size was not run)."""
    by = {r["size"]: r for r in rows}
    out: dict[str, Any] = {}
    if 2048 in by:
        for mode in ("c2f", "full"):
            m = by[2048].get(mode, {})
            if "total_s" in m:
                out[f"2048_{mode}_total_s"] = m["total_s"]
                out[f"2048_{mode}_meets"] = (m["total_s"] <= TARGETS["prep_plan_2048_s"]
                                             and m["peak_rss_gib"] <= TARGETS["prep_plan_2048_gib"])
    if 8192 in by and "total_s" in by[8192].get("c2f", {}):
        m = by[8192]["c2f"]
        out["8192_c2f_total_s"], out["8192_c2f_gib"] = m["total_s"], m["peak_rss_gib"]
        out["8192_c2f_meets"] = m["total_s"] <= TARGETS["c2f_8192_s"] and m["peak_rss_gib"] <= TARGETS["c2f_8192_gib"]
    if 4096 in by and "energy_ratio" in by[4096]:
        out["4096_energy_ratio"] = by[4096]["energy_ratio"]
        out["4096_ratio_meets"] = by[4096]["energy_ratio"] <= TARGETS["ratio_4096"]
    for mode in CHAIN_MODES:
        if 4096 in by and f"energy_ratio_{mode}" in by[4096]:
            ratio = by[4096][f"energy_ratio_{mode}"]
            out[f"4096_energy_ratio_{mode}"] = ratio
            out[f"4096_ratio_{mode}_meets"] = abs(ratio - 1.0) <= TARGETS["ratio_4096"] - 1.0
    if 32768 in by and "total_s" in by[32768].get("wc2f", {}):
        m = by[32768]["wc2f"]
        out["32768_wc2f_total_s"], out["32768_wc2f_cpu_s"], out["32768_wc2f_gib"] = m["total_s"], m["cpu_s"], m["peak_rss_gib"]
        out["32768_wc2f_meets"] = m["total_s"] <= TARGETS["wc2f_32768_s"] and m["peak_rss_gib"] <= TARGETS["wc2f_32768_gib"]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="256^2 and 512^2 only")
    parser.add_argument("--big", action="store_true", help="add 8192^2 (coarse-to-fine only; ~8 GB, minutes)")
    parser.add_argument("--huge", action="store_true",
                        help="add 16384^2 (windowed coarse-to-fine only, a shorter route; a 1 GiB temporary DEM)")
    parser.add_argument("--sizes", type=int, nargs="+", default=None, metavar="N", help="map sides (cells)")
    parser.add_argument("--factor", type=int, default=None,
                        help="coarse-to-fine downsampling factor (default: side / 256, within 4..16)")
    parser.add_argument("--seed", type=int, default=0, help="DEM seed (default 0)")
    parser.add_argument("--out", type=Path, default=None, help="write results as JSON here")
    parser.add_argument("--child", choices=["windowed", "full", "c2f", "wc2f", "tiles", *CHAIN_MODES],
                        help=argparse.SUPPRESS)
    parser.add_argument("--tif", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--start", type=float, nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--goal", type=float, nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--budget", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.child, args.tif, args.factor or 8, tuple(args.start), tuple(args.goal),
                               args.budget)))
        return 0
    sizes = args.sizes or ([256, 512] if args.quick else [512, 2048, 4096] + ([8192] if args.big else []))
    sizes = sizes + ([16384] if args.huge and 16384 not in sizes else [])
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    rows = run(sizes, args.factor, args.seed)
    for r in rows:
        if "read_s" in r.get("tiles", {}):
            r["continent"] = continent_plan(r["tiles"], r["wc2f"], r["size"])
    print_table(rows)
    print_chained(rows)
    print_tiles(rows)
    print(f"\nload average (1 / 5 / 15 min) at the start {load0}, at the end {os.getloadavg()} "
          f"on {os.cpu_count()} CPUs")
    targets = check_targets(rows)
    print("\ntargets:", json.dumps(targets))
    result = {"benchmark": "map_scale", "sizes": sizes, "factor": args.factor, "seed": args.seed, "rows": rows,
              "targets": TARGETS, "checked": targets, "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
              "platform": platform.platform(), "load_start": load0, "load_end": os.getloadavg()},
              "wall_s": time.perf_counter() - t0}
    if args.out is not None:
        from terrawatt_base.atomic import write_json_atomic

        write_json_atomic(args.out, result)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
