"""Navigator benchmark: an hour of driving replayed through :class:`planner.Navigator` on one core.

On a seeded procedural 512 x 512 map of 1 m cells (grounds: the asphalt, grass, sand and snow
presets) whose registry serves every cell with one prior (:class:`energy.LinearCurrentModel`
fitted on asphalt, :func:`planner.missions.fit_prior_model`; :meth:`CellModelRegistry.from_terrain`),
the script

1. **builds a 1-hour drive** once: a serpentine of goal points over the lower three quarters of
   the map, each stretch a lattice route on the prior's costs driven by the truth simulator
   (:meth:`energy.TruthSimulator.run_drive`, 100 Hz drive stream and IMU, leg after leg on one
   clock), cut at 3600 s and the drive stream resampled to 15 Hz
   (:meth:`InteractionLog.resample`; the IMU keeps its 100 Hz). It is cached under ``out/``
   (``navigator_bench_drive_*.npz``; generated data, never committed) so reruns start at once;
2. **replays it** with :func:`planner.missions.replay.replay_drive` (``mode="drive"``, chunks of
   0.1 s and 1 s, manoeuvres declined: the recording has none) and reports the wall time and
   the drive duration / wall time (target >= 60x real time);
3. **times each call** in its own loop over the same chunks (cut by index, outside the timing):
   ``observe`` without a checkpoint (p50 / p99 / max, target p99 <= 5 ms), checkpoints without
   an update, and checkpoints whose update is accepted and the route repaired (the observe
   call, plus the ``decline_manoeuvre`` it may trigger; target <= 100 ms). The prior is asphalt
   on every cell, so the first checkpoint on grass, sand or snow (truth ground != prior
   ground) flags its class and the driven data update it (``update_source="driven"``);
4. **beside the simulated loop**: :func:`planner.run_adaptive_mission` on the same map and the
   same stretches (one mission per stretch, the registry carried over), with the wall time
   split between the navigator (its public calls) and the truth simulator; and the replay's
   wall time as a ratio to the same run's baseline of only cutting the chunks
   (``replay_drive``'s own cutting, and a cut by index);
5. ``Navigator.save`` (and ``load``) time and state size on the 512^2 map after a quarter of
   the hour and at its end, and memory: the process's RSS every 5 min of drive in the
   per-call loop, its peak (``getrusage``), and what the navigator holds at the end (the
   series, the battery draw, the decision log, the bounded driven history).

Where a target is missed the script profiles (cProfile) the replay and prints where the time
goes (``--profile auto``, the default). Threads: ``OMP_NUM_THREADS``/BLAS/numba set to 1 before
numpy is imported, and the process pinned to one CPU (Linux). Times are never asserted in tests
(``tests/benchmarks/test_navigator_bench.py`` runs ``--quick`` and checks the structure).

Usage::

    python benchmarks/navigator_bench.py                         # 512^2, 1 h, out/navigator_bench.json
    python benchmarks/navigator_bench.py --quick --out out/nb_quick.json   # 96^2, 2 min
    python benchmarks/navigator_bench.py --seed 7 --profile always
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"  # one core: set before numpy / numba are imported

import argparse  # noqa: E402
import contextlib  # noqa: E402
import cProfile  # noqa: E402
import ctypes  # noqa: E402
import dataclasses  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import pstats  # noqa: E402
import resource  # noqa: E402
import shutil  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from energy import Battery, InteractionLog, LogMeta, TruthSimulator, ground_preset, robot_preset  # noqa: E402
from energy.logs.arrays import DRIVE_FIELDS, IMU_FIELDS  # noqa: E402
from planner import AdaptiveSettings, LearnedEnergyModel, Navigator, plan_route, warm_up_kernels  # noqa: E402
from planner.missions import NavigatorModels, ReplayFeed, fit_prior_model, run_adaptive_mission  # noqa: E402
from planner.missions import adaptive as adaptive_module  # noqa: E402
from planner.missions import replay as replay_module  # noqa: E402
from planner.missions.replay import replay_drive  # noqa: E402
from planner.registry import CellModelRegistry  # noqa: E402
from terrain.procedural import procedural_map  # noqa: E402
from terrawatt_base.atomic import write_json_atomic  # noqa: E402

GROUNDS = ("asphalt", "grass", "sand", "snow")
PRIOR_GROUND = "asphalt"
SPEED_MPS = 0.5
DRIVE_RATE_HZ = 15.0  # the drive stream as replayed; the IMU stays at the simulator's 100 Hz
SIM_RATE_HZ = 100.0
CHUNKS_S = (0.1, 1.0)
LATENCY_CHUNK_S = 0.1
EVIDENCE_S = 0.5  # a cell's evidence before it may be flagged: the default 50 samples at 100 Hz
RSS_EVERY_S = 300.0  # drive time between RSS samples in the per-call loop
DRIVE_VERSION = 1  # bump when the drive's generation changes (the cache file name holds it)
TARGETS = {"real_time_factor": 60.0, "observe_p99_ms": 5.0, "update_repair_ms": 100.0}
FULL = {"size": 512, "duration_s": 3600.0}
QUICK = {"size": 96, "duration_s": 120.0}
OUT_DIR = Path("out")


# ======================================================================== world and drive
def settings_for(seed: int, rate_hz: float = DRIVE_RATE_HZ, *, scaled: bool = True) -> AdaptiveSettings:
    """The navigator's settings: learn from driven data (the recording has no manoeuvres).

    The default policy asks for ``min_samples=50`` samples in a cell before flagging it: 0.5 s
    of evidence at the simulator's 100 Hz, but more than a 1 m cell ever gets in one pass at
    15 Hz and 0.5 m/s (30). ``scaled`` keeps the 0.5 s: ``ceil(0.5 * rate_hz)`` samples."""
    base = AdaptiveSettings(update_source="driven", speed_mps=SPEED_MPS, seed=seed)
    if not scaled:
        return base
    n = max(1, math.ceil(EVIDENCE_S * rate_hz))
    return dataclasses.replace(base, policy=dataclasses.replace(base.policy, min_samples=n))


def build_world(size: int, seed: int) -> dict[str, Any]:
    """Map, truth simulator, the prior model and its cost (a registry per navigator: updates change it)."""
    robot = robot_preset("husky")
    tmap = procedural_map((size, size), 1.0, seed=seed, grounds=GROUNDS)
    truth = TruthSimulator(robot, {g: ground_preset(g) for g in GROUNDS}, current_rate_hz=SIM_RATE_HZ,
                           accel_rate_hz=SIM_RATE_HZ, seed=seed)
    prior = fit_prior_model(truth, PRIOR_GROUND, seed=seed % 10_000)
    world = {"robot": robot, "map": tmap, "truth": truth, "prior": prior, "seed": seed, "size": size}
    cost = LearnedEnergyModel(registry(world), robot, ground_preset(PRIOR_GROUND)).energy_cost(tmap, SPEED_MPS)
    labels = cost.components()
    main = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
    world.update(cost=cost, labels=labels, main=main)
    world["goal_points"] = serpentine(world)
    world["nav_goal"] = free_point(world, (0.01, 0.99))  # the far corner: never reached by the drive
    return world


def registry(world: dict[str, Any]) -> CellModelRegistry:
    """A fresh registry: the asphalt prior on every cell."""
    return CellModelRegistry.from_terrain(world["map"], world["prior"], prior_name=f"prior-{PRIOR_GROUND}")


def battery() -> Battery:
    return Battery(40.0, 24.0)


def free_point(world: dict[str, Any], frac: tuple[float, float]) -> tuple[float, float]:
    """The free cell of the main connected region nearest to a fraction of the map (x, y)."""
    cost = world["cost"]
    rows, cols = cost.shape
    r0, c0 = frac[1] * (rows - 1), frac[0] * (cols - 1)
    rr, cc = np.nonzero((~cost.blocked) & (world["labels"] == world["main"]))
    k = int(np.argmin((rr - r0) ** 2 + (cc - c0) ** 2))
    x, y = world["map"].xy(rr[k], cc[k])
    return (float(x), float(y))


def serpentine(world: dict[str, Any]) -> list[tuple[float, float]]:
    """Goal points of the drive: four rows across the lower three quarters of the map, left-right-left...;
    then back down the same way (as often as needed)."""
    side = world["size"]
    m = max(0.05, 3.0 / side)
    ys = np.linspace(m, 0.75, 4)
    pts: list[tuple[float, float]] = []
    for i, y in enumerate(ys):
        xs = (m, 1.0 - m) if i % 2 == 0 else (1.0 - m, m)
        pts += [(xs[0], float(y)), (xs[1], float(y))]
    loop = pts + pts[::-1][1:]
    return [free_point(world, f) for f in loop * 3]


def drive_path(world: dict[str, Any], duration_s: float, cache_dir: Path = OUT_DIR) -> Path:
    return Path(cache_dir) / (f"navigator_bench_drive_v{DRIVE_VERSION}_s{world['size']}_seed{world['seed']}_"
                      f"{int(round(duration_s))}s.npz")


def build_drive(world: dict[str, Any], duration_s: float) -> tuple[InteractionLog, dict[str, Any]]:
    """Drive the serpentine with the truth simulator stretch after stretch until ``duration_s``; cut there,
    the drive stream resampled to 15 Hz. Returns the log and how it was made."""
    tmap, truth, cost = world["map"], world["truth"], world["cost"]
    pts = world["goal_points"]
    logs: list[InteractionLog] = []
    heading, t_end, total, stretches = None, None, 0.0, []
    dt = 1.0 / SIM_RATE_HZ
    for i, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
        if total >= duration_s:
            break
        if math.hypot(b[0] - a[0], b[1] - a[1]) < 1.0:
            continue
        route = plan_route(tmap, a, b, cost=cost, planner="lattice", compare=False, seed=world["seed"])
        if not route.found:
            raise RuntimeError(f"no route between goal points {a} and {b}")
        log = truth.run_drive(tmap, route.waypoints_m, speed_mps=SPEED_MPS, start_heading_rad=heading,
                              seed=world["seed"] + 100 + i).log
        if t_end is not None:
            log = log.shifted(t_end + dt - float(log.time_s[0]))
        heading = float(log.pose_xyh[-1, 2])
        t_end = float(max(log.time_s[-1], log.accel_time_s[-1]))
        total += float(log.duration_s)
        logs.append(log)
        stretches.append({"from": list(a), "to": list(b), "length_m": float(route.length_m),
                          "duration_s": float(log.duration_s)})
    whole = InteractionLog.concatenate(logs)
    t0 = float(whole.time_s[0])
    cut = whole.slice(t0, t0 + duration_s + 1e-9)
    return cut.resample(DRIVE_RATE_HZ), {"stretches": stretches}


def load_or_build_drive(world: dict[str, Any], duration_s: float, rebuild: bool = False,
                        cache_dir: Path = OUT_DIR) -> tuple[InteractionLog, dict[str, Any]]:
    """The cached drive (``<cache_dir>/navigator_bench_drive_*.npz``), built first when missing."""
    path = drive_path(world, duration_s, cache_dir)
    if path.is_file() and not rebuild:
        t0 = time.perf_counter()
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        info = json.loads(str(arrays.pop("info_json")))
        meta = LogMeta(**info.pop("meta"))
        log = InteractionLog(**arrays, meta=meta)
        info.update(cached=True, load_s=time.perf_counter() - t0, path=str(path))
        return log, info
    t0 = time.perf_counter()
    log, info = build_drive(world, duration_s)
    info["build_s"] = time.perf_counter() - t0
    arrays = {name: np.asarray(getattr(log, name)) for name in ("time_s", "accel_time_s", "pose_xyh", *DRIVE_FIELDS,
                                                                 *IMU_FIELDS) if getattr(log, name) is not None}
    if log.ground is not None:
        arrays["ground"] = np.asarray(log.ground, dtype=str)
    doc = dict(info, meta=dataclasses.asdict(log.meta))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, info_json=np.array(json.dumps(doc)), **arrays)
    os.replace(tmp, path)
    info.update(cached=False, path=str(path))
    return log, info


# ======================================================================== chunks
def index_chunks(log: InteractionLog, chunk_s: float) -> list[InteractionLog]:
    """The log cut on a grid of ``chunk_s`` from its first sample, by index (searchsorted, contiguous
    slices); a window without an IMU sample joins the next one."""
    t, ta = log.time_s, log.accel_time_s
    t0 = float(t[0])
    n = int(math.floor((float(t[-1]) - t0) / chunk_s)) + 1
    edges = t0 + chunk_s * np.arange(n + 1)
    di = np.searchsorted(t, edges, side="left")
    ai = np.searchsorted(ta, edges, side="left")
    out = []
    d0, a0 = int(di[0]), int(ai[0])
    for k in range(1, n + 1):
        d1, a1 = int(di[k]), int(ai[k])
        if d1 == d0 or (a1 == a0 and k < n):
            continue  # nothing here yet: the window joins the next one
        out.append(_cut(log, d0, d1, a0, max(a1, a0 + 1)))
        d0, a0 = d1, a1
    return out


def _cut(log: InteractionLog, d0: int, d1: int, a0: int, a1: int) -> InteractionLog:
    def part(name: str, lo: int, hi: int) -> Any:
        v = getattr(log, name)
        return None if v is None else v[lo:hi]

    return InteractionLog(time_s=log.time_s[d0:d1], **{f: part(f, d0, d1) for f in DRIVE_FIELDS},
                          accel_time_s=log.accel_time_s[a0:a1], **{f: part(f, a0, a1) for f in IMU_FIELDS},
                          pose_xyh=part("pose_xyh", d0, d1), ground=part("ground", d0, d1), meta=log.meta)


def replay_chunks(log: InteractionLog, chunk_s: float) -> list[InteractionLog]:
    """The chunks ``replay_drive`` cuts (its own private function: boolean windows over the whole log)."""
    return replay_module.drive_chunks(log, chunk_s, -math.inf)  # the exact cutting replay_drive times


# ======================================================================== measurement helpers
def rss_mib() -> float:
    """Resident set size now (MiB), from /proc (Linux); NaN elsewhere."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return math.nan


def malloc_trim() -> bool:
    """Hand the C heap's free pages back to the system (glibc); whether it could."""
    try:
        return bool(ctypes.CDLL("libc.so.6").malloc_trim(0))
    except (OSError, AttributeError):
        return False


def peak_rss_mib() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 2**20 if sys.platform == "darwin" else r / 1024.0


def dir_bytes(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def pct(values: list[float], q: float) -> float | None:
    return float(np.percentile(np.asarray(values, dtype=np.float64), q)) if values else None


def stats_ms(values_s: list[float]) -> dict[str, Any]:
    ms = [1e3 * v for v in values_s]
    return {"n": len(ms), "p50_ms": pct(ms, 50), "p99_ms": pct(ms, 99), "max_ms": max(ms) if ms else None,
            "mean_ms": float(np.mean(ms)) if ms else None, "total_s": float(sum(values_s))}


def _array_bytes(a: np.ndarray, seen: set[int]) -> int:
    """Bytes an array keeps alive: its header, and its data buffer (its base's, for a view) once."""
    n = sys.getsizeof(a) if a.flags.owndata else 112
    base = a if a.flags.owndata else a.base
    while isinstance(base, np.ndarray) and not base.flags.owndata and base.base is not None:
        base = base.base
    if isinstance(base, np.ndarray) and id(base) not in seen:
        seen.add(id(base))
        n += base.nbytes if not a.flags.owndata else 0
    return n


def held_by(nav: Navigator) -> dict[str, Any]:
    """What the navigator holds that grows with the drive (the series), and what is bounded."""
    seen: set[int] = set()
    series_arrays = [a for parts in nav.charge.series.values() for a in parts]
    draw_arrays = [a for pair in nav.charge.draw for a in pair]
    samples = int(sum(a.size for a in nav.charge.series["t"]))
    hist_s = float(sum(float(s.duration_s) for s, _, _ in nav.history))
    hist_bytes = sum(int(np.asarray(getattr(s, f)).nbytes) for s, r, c in nav.history
                     for f in ("time_s", "accel_time_s", "pose_xyh", *DRIVE_FIELDS, *IMU_FIELDS)
                     if getattr(s, f) is not None) + sum(r.nbytes + c.nbytes for _, r, c in nav.history)
    return {
        "series_samples": samples,
        "series_arrays": len(series_arrays),
        "series_bytes": sum(_array_bytes(a, seen) for a in series_arrays),
        "series_data_bytes": int(sum(a.nbytes for a in series_arrays)),
        "draw_arrays": len(draw_arrays),
        "draw_bytes": sum(_array_bytes(a, seen) for a in draw_arrays),
        "decisions": len(nav.decisions),
        "decisions_json_bytes": len(json.dumps(nav.decisions)),
        "legs": len(nav.legs),
        "history_legs": len(nav.history),
        "history_s": hist_s,
        "history_bytes": int(hist_bytes),
        "segment_chunks": len(nav.segment),
    }


@contextlib.contextmanager
def timed_calls(patches: list[tuple[Any, str, str]], last: dict[str, Any] | None = None
                ) -> Iterator[dict[str, float]]:
    """Time calls of ``owner.name`` into buckets while the block runs (outermost calls only); restored after.
    ``last["self"]`` is the first argument of the last ``"navigator"`` call (the navigator)."""
    acc: dict[str, float] = {bucket: 0.0 for _, _, bucket in patches}
    calls: dict[str, int] = {bucket: 0 for _, _, bucket in patches}
    depth: dict[str, int] = {bucket: 0 for _, _, bucket in patches}
    saved = []
    for owner, name, bucket in patches:
        orig = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
        saved.append((owner, name, orig))

        def wrapper(*args: Any, _orig: Any = orig, _b: str = bucket, **kwargs: Any) -> Any:
            depth[_b] += 1
            if last is not None and _b == "navigator" and args:
                last["self"] = args[0]
            t0 = time.perf_counter()
            try:
                return _orig(*args, **kwargs)
            finally:
                depth[_b] -= 1
                if depth[_b] == 0:
                    acc[_b] += time.perf_counter() - t0
                    calls[_b] += 1

        setattr(owner, name, wrapper)
    try:
        yield acc
    finally:
        for owner, name, orig in reversed(saved):
            setattr(owner, name, orig)
        acc.update({f"{b}_calls": float(n) for b, n in calls.items()})


# ======================================================================== the parts
def run_replay(world: dict[str, Any], log: InteractionLog, chunk_s: float, *, profile: bool = False,
               scaled: bool = True) -> tuple[dict[str, Any], cProfile.Profile | None]:
    """``replay_drive`` of the whole drive in chunks of ``chunk_s``: wall time, real-time factor, outcome."""
    prof = cProfile.Profile() if profile else None
    t0 = time.perf_counter()
    if prof is not None:
        prof.enable()
    res = replay_drive(Navigator(world["map"], registry(world), world["robot"], battery(), world["nav_goal"],
                                 settings=settings_for(world["seed"], scaled=scaled),
                                 models=NavigatorModels(physics_ground=ground_preset(PRIOR_GROUND))), [log],
                       feed=ReplayFeed(mode="drive", chunk_s=chunk_s))
    if prof is not None:
        prof.disable()
    total = time.perf_counter() - t0
    nav = res.navigator
    return {
        "chunk_s": chunk_s, "min_samples": nav.settings.policy.min_samples, "chunks": res.chunks,
        "drive_s": res.drive_time_s, "wall_s": res.wall_time_s,
        "plan_and_setup_s": total - res.wall_time_s,
        "real_time_factor": res.drive_time_s / max(res.wall_time_s, 1e-12),
        "status": nav.status if nav.finished else "under_way", "unused_s": res.unused_s,
        "checkpoints": len(nav.legs), "updates_accepted": sum(u.accepted for u in nav.updates),
        "updates_tried": len(nav.updates), "replans": len(nav.replans) - 1,
        "update_grounds": [u.ground for u in nav.updates if u.accepted],
    }, prof


def run_calls(world: dict[str, Any], log: InteractionLog, chunk_s: float, *, state_dir: Path | None,
              save_at_s: float | None) -> dict[str, Any]:
    """Own loop over chunks cut beforehand: each observe (and the declines it triggers) timed and classified;
    RSS along the drive; save/load at ``save_at_s`` and at the end."""
    rss_start, peak_start = rss_mib(), peak_rss_mib()
    t0 = time.perf_counter()
    chunks = index_chunks(log, chunk_s)
    cut_s = time.perf_counter() - t0
    rss_chunks = rss_mib()
    nav = Navigator(world["map"], registry(world), world["robot"], battery(), world["nav_goal"],
                    settings=settings_for(world["seed"]),
                    models=NavigatorModels(physics_ground=ground_preset(PRIOR_GROUND)))
    t = log.time_s
    t0 = time.perf_counter()
    nav.plan(tuple(log.pose_xyh[0, :2]), time_s=float(t[0]) - float(t[1] - t[0]))
    plan_s = time.perf_counter() - t0
    cats: dict[str, list[float]] = {"observe": [], "checkpoint_no_update": [], "checkpoint_update_rejected": [],
                                    "checkpoint_update_repair": []}
    repair_events: list[dict[str, Any]] = []
    max_single = {k: 0.0 for k in cats}
    rss_planned = rss_mib()
    rss = [{"drive_s": 0.0, "rss_mib": rss_planned}]
    saves: list[dict[str, Any]] = []
    next_rss = RSS_EVERY_S
    saved_mid = save_at_s is None
    t_first = float(t[0])
    loop_wall = 0.0
    gen2_before = gc.get_stats()[2]["collections"]
    declined = 0
    for ch in chunks:
        if nav.finished:
            break
        n_up, n_acc, n_rep = len(nav.updates), sum(u.accepted for u in nav.updates), len(nav.replans)
        w = time.perf_counter()
        d = nav.observe(ch)
        single = [time.perf_counter() - w]
        while d.action == "manoeuvre":  # the recording holds no manoeuvre: decline it
            w1 = time.perf_counter()
            d = nav.decline_manoeuvre("not in the recording")
            single.append(time.perf_counter() - w1)
            declined += 1
        wall = sum(single)
        loop_wall += wall
        acc = sum(u.accepted for u in nav.updates) - n_acc
        if d.checkpoint is None and len(single) == 1:
            cat = "observe"
        elif acc > 0:
            cat = "checkpoint_update_repair"
            new = nav.updates[n_up:]
            rep = nav.replans[n_rep:]
            repair_events.append({
                "drive_s": float(ch.time_s[-1]) - t_first, "wall_ms": 1e3 * wall, "calls": len(single),
                "grounds": [u.ground for u in new if u.accepted], "scope_cells": [u.scope_cells for u in new],
                "fit_validate_ms": 1e3 * sum(u.wall_time_s for u in new),
                "refresh_ms": 1e3 * sum(r.refresh_time_s for r in rep),
                "search_ms": 1e3 * sum(r.planning_time_s for r in rep),
                "route_changed": any(r.route_changed for r in rep), "replans": len(rep),
            })
        elif len(nav.updates) > n_up:
            cat = "checkpoint_update_rejected"
        else:
            cat = "checkpoint_no_update"
        cats[cat].append(wall)
        max_single[cat] = max(max_single[cat], max(single))
        now = float(ch.time_s[-1]) - t_first
        if now >= next_rss:
            rss.append({"drive_s": now, "rss_mib": rss_mib()})
            next_rss += RSS_EVERY_S
        if not saved_mid and now >= save_at_s and state_dir is not None:
            saves.append(save_load(nav, world, state_dir / "quarter", now))
            saved_mid = True
    rss.append({"drive_s": float(nav.time_s) - t_first, "rss_mib": rss_mib()})
    peak_loop = peak_rss_mib()
    gen2 = gc.get_stats()[2]["collections"] - gen2_before
    gc.collect()  # what is garbage (reference cycles) and what is held
    rss_gc = rss_mib()
    trimmed = malloc_trim()
    rss_trim = rss_mib()
    held = held_by(nav)
    save_prof = None
    if state_dir is not None:
        saves.append(save_load(nav, world, state_dir / "end", float(nav.time_s) - t_first))
        save_prof = cProfile.Profile()
        save_prof.enable()
        nav.save(state_dir / "end")
        save_prof.disable()
    memory = {"rss_before_mib": rss_start, "rss_after_cutting_mib": rss_chunks,
              "rss_after_plan_mib": rss_planned, "rss_end_mib": rss[-1]["rss_mib"],
              "peak_rss_before_mib": peak_start, "peak_rss_after_loop_mib": peak_loop,
              "navigator_at_plan_mib": rss_planned - rss_chunks, "growth_over_drive_mib": rss[-1]["rss_mib"] - rss_planned,
              "chunk_list_mib": rss_chunks - rss_start, "full_gc_passes_during_drive": gen2,
              "rss_after_gc_mib": rss_gc, "malloc_trim": trimmed, "rss_after_gc_and_trim_mib": rss_trim,
              "held_growth_mib": rss_trim - rss_planned}
    drive_s = float(nav.time_s) - t_first
    return {
        "chunk_s": chunk_s, "chunks": len(chunks), "cut_by_index_s": cut_s, "plan_s": plan_s,
        "navigator_s": loop_wall, "drive_s": drive_s,
        "real_time_factor": drive_s / max(loop_wall, 1e-12),
        "status": nav.status if nav.finished else "under_way", "declined_manoeuvres": declined,
        "calls": {k: stats_ms(v) for k, v in cats.items()},
        "max_single_call_ms": {k: 1e3 * v for k, v in max_single.items()},
        "update_repair_events": repair_events,
        "updates": [{"after_leg": u.after_leg, "ground": u.ground, "kind": u.kind, "accepted": bool(u.accepted),
                     "scope_cells": u.scope_cells, "wall_ms": 1e3 * u.wall_time_s} for u in nav.updates],
        "rss": rss, "memory": memory, "held": held, "saves": saves,
        "save_profile": None if save_prof is None else callee_tree(save_prof, "write_navigator_state", depth=2,
                                                                   min_share=0.03),
    }


def save_load(nav: Navigator, world: dict[str, Any], path: Path, drive_s: float) -> dict[str, Any]:
    """``nav.save`` (twice: a first write, then the replacement of an existing state) and ``Navigator.load``."""
    if path.exists():
        shutil.rmtree(path)
    w = time.perf_counter()
    nav.save(path)
    first = time.perf_counter() - w
    w = time.perf_counter()
    nav.save(path)
    again = time.perf_counter() - w
    w = time.perf_counter()
    Navigator.load(path, world["map"])
    load = time.perf_counter() - w
    sizes = {p.name: (dir_bytes(p) if p.is_dir() else p.stat().st_size) for p in path.iterdir()}
    return {"drive_s": drive_s, "save_s": first, "save_again_s": again, "load_s": load,
            "bytes": dir_bytes(path), "parts_bytes": sizes, "legs": len(nav.legs)}


def run_simulated(world: dict[str, Any], stretches: int) -> dict[str, Any]:
    """``run_adaptive_mission`` over the drive's stretches, one mission each from the prior registry (a
    registry carried from one navigator to the next fails: each navigator names its updates
    ``update1-...`` again); the wall time split between the navigator's calls, the truth simulator
    and the rest (the client)."""
    pts = world["goal_points"][: stretches + 1]
    patches = [(Navigator, name, "navigator") for name in ("plan", "observe", "observe_manoeuvre",
                                                           "decline_manoeuvre")]
    patches += [(adaptive_module, "simulate_mission", "simulator"), (TruthSimulator, "simulate_commands", "simulator")]
    missions, sim_drive_s, legs, ups = [], 0.0, 0, 0
    last: dict[str, Any] = {"self": None}
    w0 = time.perf_counter()
    with timed_calls(patches, last) as acc:
        for i, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
            if math.hypot(b[0] - a[0], b[1] - a[1]) < 1.0:
                continue
            reg = registry(world)
            lem = LearnedEnergyModel(reg, world["robot"], ground_preset(PRIOR_GROUND))
            try:
                res = run_adaptive_mission(Navigator(world["map"], reg, world["robot"], battery(), b,
                                                     settings=dataclasses.replace(settings_for(world["seed"], SIM_RATE_HZ),
                                                                                  seed=world["seed"] + i),
                                                     models=NavigatorModels(physics_ground=ground_preset(PRIOR_GROUND),
                                                                            learned=lem)),
                                           world["truth"], a)
            except Exception as exc:  # noqa: BLE001 - a library error: recorded, the next stretch goes on
                nav = last["self"]
                span = float(nav.time_s) if nav is not None and math.isfinite(nav.time_s) else 0.0
                sim_drive_s += span
                n_legs = len(nav.legs) if nav is not None else 0
                legs += n_legs
                missions.append({"status": "error", "error": f"{type(exc).__name__}: {exc}", "drive_s": span,
                                 "legs": n_legs, "where": _where(exc),
                                 "updates_accepted": sum(u.accepted for u in nav.updates) if nav is not None else 0})
                ups += missions[-1]["updates_accepted"]
                continue
            span = float(res.time_s[-1] - res.time_s[0]) if res.time_s.size else 0.0
            sim_drive_s += span
            legs += len(res.legs)
            ups += sum(u.accepted for u in res.updates)
            missions.append({"status": res.status, "drive_s": span, "legs": len(res.legs),
                             "updates_accepted": sum(u.accepted for u in res.updates)})
    wall = time.perf_counter() - w0
    nav_s, sim_s = acc["navigator"], acc["simulator"]
    return {"missions": missions, "drive_s": sim_drive_s, "legs": legs, "updates_accepted": ups, "wall_s": wall,
            "navigator_s": nav_s, "simulator_s": sim_s, "client_s": wall - nav_s - sim_s,
            "navigator_share": nav_s / wall, "simulator_share": sim_s / wall,
            "client_share": (wall - nav_s - sim_s) / wall, "navigator_calls": int(acc["navigator_calls"]),
            "navigator_s_per_drive_hour": 3600.0 * nav_s / max(sim_drive_s, 1e-12),
            "real_time_factor": sim_drive_s / max(wall, 1e-12)}


def _where(exc: BaseException) -> list[str]:
    """The innermost frames of an exception (file:line function)."""
    import traceback

    return [f"{Path(f.filename).name}:{f.lineno} {f.name}" for f in traceback.extract_tb(exc.__traceback__)[-4:]]


def time_cutting(log: InteractionLog, chunk_s: float, repeats: int) -> dict[str, Any]:
    """The baseline: only cutting the chunks, as ``replay_drive`` does and by index (best of ``repeats``)."""
    rep, idx = [], []
    n = 0
    for _ in range(repeats):
        w = time.perf_counter()
        n = len(replay_chunks(log, chunk_s))
        rep.append(time.perf_counter() - w)
    for _ in range(repeats):
        w = time.perf_counter()
        index_chunks(log, chunk_s)
        idx.append(time.perf_counter() - w)
    return {"chunk_s": chunk_s, "chunks": n, "replay_cut_s": min(rep), "index_cut_s": min(idx)}


# ======================================================================== profile
def profile_summary(prof: cProfile.Profile, wall_s: float, top: int = 18) -> dict[str, Any]:
    """The functions with the most own time and the most cumulative time (share of ``wall_s``)."""
    st = pstats.Stats(prof)
    rows = []
    for (file, line, func), (_cc, nc, tt, ct, _) in st.stats.items():  # type: ignore[attr-defined]
        short = f"{Path(file).parent.name}/{Path(file).name}:{line}({func})" if line else func
        rows.append({"function": short, "calls": int(nc), "own_s": tt, "cum_s": ct})
    total = sum(r["own_s"] for r in rows)
    by_own = sorted(rows, key=lambda r: -r["own_s"])[:top]
    by_cum = sorted((r for r in rows if "terrawatt" in r["function"] or "/" in r["function"]),
                    key=lambda r: -r["cum_s"])[:top]
    for r in by_own + by_cum:
        r["own_share"], r["cum_share"] = r["own_s"] / total, r["cum_s"] / total
    return {"profiled_total_s": total, "wall_s_unprofiled": wall_s, "by_own_time": by_own, "by_cumulative": by_cum}


def callee_tree(prof: cProfile.Profile, root: str, *, depth: int = 3, min_share: float = 0.04,
                per: str | None = None) -> dict[str, Any]:
    """Where the time of the function named ``root`` goes: its callees (cumulative time in that caller),
    recursively to ``depth`` levels, those above ``min_share`` of the root. Functions are matched by
    name only (the navigator's methods may move between modules). ``per``: the function whose call
    count the times are divided by (default the root's)."""
    st = pstats.Stats(prof)
    st.calc_callees()
    funcs = {f: v for f, v in st.stats.items()}  # type: ignore[attr-defined]
    roots = [f for f in funcs if f[2] == root]
    if not roots:
        return {"root": root, "found": False}
    fr = max(roots, key=lambda f: funcs[f][3])
    total = funcs[fr][3]
    per_f = next((f for f in funcs if f[2] == per), fr) if per else fr
    n_calls = max(int(funcs[per_f][1]), 1)

    def name(f: tuple[str, int, str]) -> str:
        return f"{Path(f[0]).name}:{f[1]}({f[2]})" if f[1] else f[2]

    def walk(f: tuple[str, int, str], ct: float, level: int, seen: tuple[Any, ...]) -> dict[str, Any]:
        node: dict[str, Any] = {"function": name(f), "cum_s": ct, "share": ct / total if total else 0.0,
                                "ms_per_root_call": 1e3 * ct / n_calls}
        if level < depth:
            kids = []
            # a function called from elsewhere too: its callees' times are scaled to this branch's part of it
            scale = ct / funcs[f][3] if funcs[f][3] > 0 else 0.0
            for callee, edge in st.all_callees.get(f, {}).items():  # type: ignore[attr-defined]
                c_ct = (edge[3] if len(edge) > 3 else 0.0) * (1.0 if level == 0 else scale)
                if callee in seen or not total or c_ct / total < min_share:
                    continue
                kids.append(walk(callee, c_ct, level + 1, seen + (callee,)))
            node["callees"] = sorted(kids, key=lambda k: -k["cum_s"])
        return node

    out = walk(fr, total, 0, (fr,))
    out.update(found=True, root_calls=int(funcs[fr][1]), per=name(per_f), per_calls=n_calls)
    return out


def _tree_lines(node: dict[str, Any], indent: str = "    ") -> list[str]:
    if not node.get("found", True):
        return [f"{indent}({node['root']} not found in the profile)"]
    out = [f"{indent}{100 * node['share']:5.1f} %  {node['ms_per_root_call']:8.2f} ms/call  {node['function']}"]
    for kid in node.get("callees", []):
        out += _tree_lines(kid, indent + "  ")
    return out


def print_tree(node: dict[str, Any], indent: str = "    ") -> None:
    print("\n".join(_tree_lines(node, indent)))


def print_profile(title: str, summary: dict[str, Any]) -> None:
    print(f"\nprofile ({title}): {summary['profiled_total_s']:.1f} s under cProfile "
          f"({summary['wall_s_unprofiled']:.1f} s without)")
    for key, tree in summary.get("trees", {}).items():
        print(f"  {key} (times per call of {tree.get('per', key)}, {tree.get('per_calls', 0)} calls):")
        print_tree(tree)
    for key, label in (("by_cumulative", "cumulative"), ("by_own_time", "own time")):
        print(f"  by {label}:")
        for r in summary[key][:12]:
            print(f"    {100 * r[('cum' if key == 'by_cumulative' else 'own') + '_share']:5.1f} %  "
                  f"{r['cum_s' if key == 'by_cumulative' else 'own_s']:8.2f} s  {r['calls']:>9d} calls  {r['function']}")


# ======================================================================== run, print
def run(size: int, duration_s: float, seed: int, *, profile: str = "auto", rebuild: bool = False,
        simulated: bool = True, state_dir: Path | None = None, cache_dir: Path = OUT_DIR) -> dict[str, Any]:
    w_start = time.perf_counter()
    load_before = os.getloadavg()
    try:
        import numba

        numba.set_num_threads(1)
        numba_threads = numba.get_num_threads()
    except ImportError:  # pragma: no cover
        numba_threads = None
    compile_s = warm_up_kernels()
    t0 = time.perf_counter()
    world = build_world(size, seed)
    world_s = time.perf_counter() - t0
    log, drive_info = load_or_build_drive(world, duration_s, rebuild, cache_dir)
    n_stretches = len(drive_info["stretches"])
    ground = np.asarray(world["map"].ground)
    drive = {"duration_s": float(log.duration_s), "drive_rate_hz": float(log.drive_rate_hz),
             "imu_rate_hz": float(log.accel_rate_hz), "drive_samples": len(log),
             "imu_samples": int(log.accel_time_s.size), "stretches": n_stretches,
             "length_m": float(np.hypot(*np.diff(log.pose_xyh[:, :2], axis=0).T).sum()),
             "ground_share": {g: float(np.mean(np.asarray(log.ground) == g)) for g in GROUNDS},
             **{k: v for k, v in drive_info.items() if k != "stretches"}}
    result: dict[str, Any] = {
        "benchmark": "navigator", "map_cells": [size, size], "cell_size_m": 1.0, "seed": seed,
        "grounds": list(GROUNDS), "prior_ground": PRIOR_GROUND,
        "map_ground_share": {g: float(np.mean(ground == i)) for i, g in enumerate(GROUNDS)},
        "settings": dataclasses.asdict(settings_for(seed)),
        "start_xy_m": [float(v) for v in log.pose_xyh[0, :2]], "nav_goal_xy_m": list(world["nav_goal"]),
        "drive": drive, "targets": TARGETS, "numba_warm_up_s": compile_s, "world_s": world_s,
    }
    # the per-call loops first: the 0.1 s one measures memory from a clean process (nothing else built yet)
    tmp = None
    if state_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="navigator_bench_")
        state_dir = Path(tmp.name)
    try:
        result["calls"] = []
        for c in CHUNKS_S:
            row = run_calls(world, log, c, state_dir=state_dir if c == LATENCY_CHUNK_S else None,
                            save_at_s=duration_s / 4 if c == LATENCY_CHUNK_S else None)
            result["calls"].append(row)
            print(f"  per-call loop chunk {c:g} s: navigator {row['navigator_s']:.1f} s", flush=True)
    finally:
        if tmp is not None:
            tmp.cleanup()
    # the baseline of cutting only, then the replays (replay_drive)
    result["cutting"] = [time_cutting(log, c, 1 if duration_s > 600 else 3) for c in CHUNKS_S]
    result["replay"] = []
    for c in CHUNKS_S:
        row, _ = run_replay(world, log, c)
        cut = next(x for x in result["cutting"] if x["chunk_s"] == c)
        row["wall_over_replay_cut"] = row["wall_s"] / max(cut["replay_cut_s"], 1e-12)
        row["wall_over_index_cut"] = row["wall_s"] / max(cut["index_cut_s"], 1e-12)
        result["replay"].append(row)
        print(f"  replay chunk {c:g} s: {row['wall_s']:.1f} s wall, {row['real_time_factor']:.1f}x real time",
              flush=True)
    # the library's default policy (min_samples=50) on the 15 Hz stream: does anything get flagged?
    result["replay_default_policy"], _ = run_replay(world, log, CHUNKS_S[-1], scaled=False)
    # beside the simulated loop
    if simulated:
        result["simulated"] = run_simulated(world, n_stretches)
        print(f"  simulated loop: {result['simulated']['wall_s']:.1f} s wall", flush=True)
    result["ratios"] = ratios(result)
    result["targets_met"] = targets_met(result)
    # where the time goes: observe in 0.1 s chunks; the checkpoints (update + repair) in 1 s chunks
    missed = not all(result["targets_met"].values())
    if profile == "always" or (profile == "auto" and missed):
        result["profile"] = {}
        trees = {0.1: [("observe", None), ("_checkpoint", None)],
                 1.0: [("_checkpoint", None), ("_replan", None)]}
        for c in CHUNKS_S:
            row = next(r for r in result["replay"] if r["chunk_s"] == c)
            _, prof = run_replay(world, log, c, profile=True)
            summary = profile_summary(prof, row["wall_s"])
            summary["trees"] = {root: callee_tree(prof, root, depth=3 if root != "observe" else 2,
                                                  min_share=0.03 if root != "observe" else 0.02)
                                for root, _ in trees.get(c, [])}
            summary["trees"]["replay_drive"] = callee_tree(prof, "replay_drive", depth=1, min_share=0.02)
            result["profile"][f"replay_chunk_{c:g}s"] = summary
            print(f"  profiled replay chunk {c:g} s", flush=True)
    result["peak_rss_mib"] = peak_rss_mib()
    result["load_average_before"] = list(load_before)
    result["load_average_after"] = list(os.getloadavg())
    result["machine"] = {"python": platform.python_version(), "cpus": os.cpu_count(), "platform": platform.platform(),
                         "affinity": sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
                         "numba_threads": numba_threads,
                         "threads_env": {v: os.environ.get(v) for v in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS")}}
    result["wall_time_s"] = time.perf_counter() - w_start
    return result


def ratios(res: dict[str, Any]) -> dict[str, Any]:
    rp = {r["chunk_s"]: r for r in res["replay"]}
    calls = {r["chunk_s"]: r for r in res["calls"]}
    cut = {r["chunk_s"]: r for r in res["cutting"]}
    out: dict[str, Any] = {}
    for c in CHUNKS_S:
        out[f"chunk_{c:g}s"] = {
            "replay_wall_over_cut_only": rp[c]["wall_s"] / max(cut[c]["replay_cut_s"], 1e-12),
            "replay_cut_share_of_replay_wall": cut[c]["replay_cut_s"] / max(rp[c]["wall_s"], 1e-12),
            "navigator_share_of_replay_wall": calls[c]["navigator_s"] / max(rp[c]["wall_s"], 1e-12),
            "replay_cut_over_index_cut": cut[c]["replay_cut_s"] / max(cut[c]["index_cut_s"], 1e-12),
        }
    sim = res.get("simulated")
    if sim:
        nav_hour = 3600.0 * calls[LATENCY_CHUNK_S]["navigator_s"] / max(calls[LATENCY_CHUNK_S]["drive_s"], 1e-12)
        out["navigator_per_drive_hour_replay_0.1s_over_simulated"] = nav_hour / max(sim["navigator_s_per_drive_hour"],
                                                                                   1e-12)
        out["simulated_navigator_over_simulator"] = sim["navigator_s"] / max(sim["simulator_s"], 1e-12)
    return out


def targets_met(res: dict[str, Any]) -> dict[str, bool]:
    rp = {r["chunk_s"]: r for r in res["replay"]}
    lat = next(r for r in res["calls"] if r["chunk_s"] == LATENCY_CHUNK_S)
    ur = lat["calls"]["checkpoint_update_repair"]
    out = {f"replay_{c:g}s_real_time": rp[c]["real_time_factor"] >= TARGETS["real_time_factor"] for c in CHUNKS_S}
    out["observe_p99"] = (lat["calls"]["observe"]["p99_ms"] or 0.0) <= TARGETS["observe_p99_ms"]
    out["update_repair"] = ur["n"] == 0 or ur["max_ms"] <= TARGETS["update_repair_ms"]
    return out


def _f(v: Any, spec: str = ".1f") -> str:
    return "-" if v is None else format(v, spec)


def format_table(res: dict[str, Any]) -> str:
    d = res["drive"]
    lines = [
        f"navigator benchmark: {res['map_cells'][0]}^2 cells of 1 m, seed {res['seed']}, prior {res['prior_ground']!r} "
        f"on every cell; drive {d['duration_s']:.0f} s, {d['length_m']:.0f} m, {d['stretches']} stretches, drive "
        f"stream {d['drive_rate_hz']:.0f} Hz ({d['drive_samples']} samples), IMU {d['imu_rate_hz']:.0f} Hz "
        f"({d['imu_samples']}); grounds driven " + ", ".join(f"{g} {100 * s:.0f} %" for g, s in
                                                             d["ground_share"].items()),
        f"one core (numba threads {res['machine']['numba_threads']}, affinity {res['machine']['affinity']}); load "
        f"average {res['load_average_before'][0]:.2f} before, {res['load_average_after'][0]:.2f} after",
        "",
        "1. replay_drive (mode='drive', manoeuvres declined)   target >= 60x real time",
        f"  {'chunk_s':>7} {'chunks':>7} {'wall_s':>8} {'x_real':>7} {'cut_only_s':>10} {'wall/cut':>8} "
        f"{'nav_s':>7} {'nav_share':>9} {'checkpts':>8} {'updates':>7} {'replans':>7} {'status':>10}",
    ]
    calls = {r["chunk_s"]: r for r in res["calls"]}
    cut = {r["chunk_s"]: r for r in res["cutting"]}
    for r in res["replay"]:
        c = r["chunk_s"]
        lines.append(f"  {c:>7g} {r['chunks']:>7d} {r['wall_s']:>8.2f} {r['real_time_factor']:>7.1f} "
                     f"{cut[c]['replay_cut_s']:>10.2f} {r['wall_over_replay_cut']:>8.2f} "
                     f"{calls[c]['navigator_s']:>7.2f} {calls[c]['navigator_s'] / r['wall_s']:>9.2f} "
                     f"{r['checkpoints']:>8d} {r['updates_accepted']:>7d} {r['replans']:>7d} {r['status']:>10}")
    dp = res["replay_default_policy"]
    lines.append(f"  policy min_samples {res['replay'][0]['min_samples']} (0.5 s at 15 Hz); with the library's default "
                 f"{dp['min_samples']} ({dp['chunk_s']:g} s chunks): {dp['updates_accepted']} updates accepted, "
                 f"{dp['updates_tried']} tried in {dp['checkpoints']} checkpoints")
    lines += ["  (cut_only_s: replay_drive's own chunk cutting alone; nav_s: the navigator's calls alone, chunks cut "
              "by index beforehand: " + ", ".join(f"{c:g} s -> {cut[c]['index_cut_s']:.2f} s to cut" for c in cut)
              + ")", "",
              f"2. call latency (own loop, chunks cut beforehand)   targets: observe p99 <= "
              f"{TARGETS['observe_p99_ms']:g} ms, update + repair <= {TARGETS['update_repair_ms']:g} ms",
              f"  {'chunk_s':>7} {'kind':<28} {'n':>6} {'p50_ms':>8} {'p99_ms':>8} {'max_ms':>8} {'total_s':>8}"]
    for r in res["calls"]:
        for k, s in r["calls"].items():
            lines.append(f"  {r['chunk_s']:>7g} {k:<28} {s['n']:>6d} {_f(s['p50_ms'], '.2f'):>8} "
                         f"{_f(s['p99_ms'], '.2f'):>8} {_f(s['max_ms'], '.2f'):>8} {s['total_s']:>8.2f}")
        lines.append(f"  {r['chunk_s']:>7g} {'(navigator total, x real)':<28} {r['chunks']:>6d} {'':>8} {'':>8} "
                     f"{'':>8} {r['navigator_s']:>8.2f}   {r['real_time_factor']:.0f}x real time; first plan "
                     f"{r['plan_s']:.2f} s")
    lat = calls[LATENCY_CHUNK_S]
    for e in lat["update_repair_events"]:
        lines.append(f"    update + repair at {e['drive_s']:7.1f} s: {e['wall_ms']:7.1f} ms ({e['calls']} call(s)) "
                     f"{'/'.join(e['grounds'])} ({'/'.join(str(s) for s in e['scope_cells'])} cells): fit+validate "
                     f"{e['fit_validate_ms']:.1f} ms, cost refresh {e['refresh_ms']:.1f} ms, search "
                     f"{e['search_ms']:.1f} ms, rest {e['wall_ms'] - e['fit_validate_ms'] - e['refresh_ms'] - e['search_ms']:.1f} ms; "
                     f"route changed {e['route_changed']}")
    sim = res.get("simulated")
    rat = res["ratios"]
    lines += ["", "3. beside the simulated loop (run_adaptive_mission, same map, same stretches) and ratios"]
    if sim:
        lines += [f"  simulated: {sim['drive_s']:.0f} s driven in {sim['wall_s']:.1f} s wall "
                  f"({sim['real_time_factor']:.0f}x real time), {sim['legs']} legs, {sim['updates_accepted']} updates; "
                  f"navigator {sim['navigator_s']:.1f} s ({100 * sim['navigator_share']:.0f} %), truth simulator "
                  f"{sim['simulator_s']:.1f} s ({100 * sim['simulator_share']:.0f} %), client "
                  f"{sim['client_s']:.1f} s ({100 * sim['client_share']:.0f} %); navigator/simulator "
                  f"{rat['simulated_navigator_over_simulator']:.2f}",
                  f"  navigator time per drive hour: replay in 0.1 s chunks {3600 * lat['navigator_s'] / lat['drive_s']:.1f} s "
                  f"vs simulated loop (one observe per leg) {sim['navigator_s_per_drive_hour']:.1f} s: ratio "
                  f"{rat['navigator_per_drive_hour_replay_0.1s_over_simulated']:.2f}"]
        for i, m in enumerate(sim["missions"]):
            if m["status"] == "error":
                lines.append(f"  stretch {i}: run_adaptive_mission raised after {m['drive_s']:.0f} s / {m['legs']} legs: "
                             f"{m['error']} (at {' <- '.join(reversed(m['where']))})")
    for c in CHUNKS_S:
        q = rat[f"chunk_{c:g}s"]
        lines.append(f"  chunk {c:g} s: replay wall / cutting only {q['replay_wall_over_cut_only']:.2f}; cutting "
                     f"{100 * q['replay_cut_share_of_replay_wall']:.0f} % and navigator "
                     f"{100 * q['navigator_share_of_replay_wall']:.0f} % of the replay's wall; replay_drive's cut / "
                     f"cut by index {q['replay_cut_over_index_cut']:.0f}x")
    lines += ["", "4. save / load and memory"]
    for s in lat["saves"]:
        parts = ", ".join(f"{k} {v / 2**20:.2f}" for k, v in sorted(s["parts_bytes"].items()))
        lines.append(f"  after {s['drive_s']:6.0f} s ({s['legs']} legs): save {1e3 * s['save_s']:.0f} ms "
                     f"(again {1e3 * s['save_again_s']:.0f} ms), load {1e3 * s['load_s']:.0f} ms, "
                     f"{s['bytes'] / 2**20:.2f} MiB ({parts} MiB)")
    rss = lat["rss"]
    lines.append("  RSS along the drive (0.1 s chunks): " + ", ".join(f"{r['drive_s']:.0f} s {r['rss_mib']:.0f}"
                                                                     for r in rss) + " MiB")
    h = lat["held"]
    growth = rss[-1]["rss_mib"] - rss[0]["rss_mib"]
    lines.append(f"  growth {growth:.1f} MiB over {lat['chunks']} chunks ({1024 * growth / max(lat['chunks'], 1):.2f} "
                 f"KiB/chunk); navigator holds: series {h['series_samples']} samples in {h['series_arrays']} arrays, "
                 f"{h['series_bytes'] / 2**20:.1f} MiB ({h['series_data_bytes'] / 2**20:.1f} MiB of values); "
                 f"battery draw {h['draw_arrays']} arrays {h['draw_bytes'] / 2**20:.1f} MiB; decisions "
                 f"{h['decisions']} ({h['decisions_json_bytes'] / 2**20:.2f} MiB as JSON); driven history "
                 f"{h['history_legs']} legs / {h['history_s']:.0f} s / {h['history_bytes'] / 2**20:.1f} MiB (bounded)")
    m = lat["memory"]
    lines.append(f"  RSS: {m['rss_before_mib']:.0f} MiB before (map, drive, kernels); the drive's 0.1 s chunks cut "
                 f"+{m['chunk_list_mib']:.0f} MiB; navigator built and planned +{m['navigator_at_plan_mib']:.0f} MiB; "
                 f"+{m['growth_over_drive_mib']:.0f} MiB over the drive; peak RSS {m['peak_rss_after_loop_mib']:.0f} MiB "
                 f"at the drive's end (process peak over the whole benchmark {res['peak_rss_mib']:.0f} MiB)")
    lines.append(f"  {m['full_gc_passes_during_drive']} full GC passes during the drive; after gc.collect() RSS "
                 f"{m['rss_after_gc_mib']:.0f} MiB, after malloc_trim {m['rss_after_gc_and_trim_mib']:.0f} MiB: the "
                 f"navigator holds +{m['held_growth_mib']:.0f} MiB more than after its first plan (the rest was freed "
                 "memory and garbage waiting for the cyclic GC)")
    sp = lat.get("save_profile")
    if sp and sp.get("found"):
        lines.append("  where nav.save's time goes (at the drive's end, cProfile):")
        lines += _tree_lines(sp, "    ")
    lines += ["", "targets: " + ", ".join(f"{k} {'met' if v else 'MISSED'}" for k, v in res["targets_met"].items()),
              f"benchmark wall time {res['wall_time_s']:.1f} s"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"a {QUICK['size']}^2 map and a "
                        f"{QUICK['duration_s']:g} s drive")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--size", type=int, default=None, help="map side in cells (default 512, 96 with --quick)")
    parser.add_argument("--duration-s", type=float, default=None, help="drive length (default 3600, 120 with --quick)")
    parser.add_argument("--out", type=Path, default=OUT_DIR / "navigator_bench.json")
    parser.add_argument("--profile", choices=("auto", "always", "never"), default="auto",
                        help="cProfile the replays: when a target is missed (auto), always or never")
    parser.add_argument("--no-simulated", action="store_true", help="skip the simulated loop (part 3)")
    parser.add_argument("--cache-dir", type=Path, default=OUT_DIR, help="where the generated drive is cached")
    parser.add_argument("--rebuild-drive", action="store_true", help="simulate the drive again (ignore the cache)")
    parser.add_argument("--no-pin", action="store_true", help="do not pin the process to one CPU")
    args = parser.parse_args(argv)
    preset = QUICK if args.quick else FULL
    size = args.size or preset["size"]
    duration = args.duration_s or preset["duration_s"]
    if not args.no_pin and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    res = run(size, duration, args.seed, profile=args.profile, rebuild=args.rebuild_drive,
              simulated=not args.no_simulated, cache_dir=args.cache_dir)
    res["quick"] = bool(args.quick)
    print(format_table(res))
    for title, summary in res.get("profile", {}).items():
        print_profile(title, summary)
    write_json_atomic(args.out, res, indent=1)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
