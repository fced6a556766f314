"""Fuzz every reader with mutated real files: a clear library error or a correct result, never a crash or a hang.

Seed files are written first (a current-model file with an interval, an estimator file
with network weights, a map ``.npz``, a CSV log, a BorealTC run folder, a GeoTIFF DEM, a
Husky-style ROS 1 bag, a pairs CSV). Each input is one seed
mutated in one of these ways:

- ``truncate``: cut at a random length;
- ``flip``: 1-16 random bit flips;
- ``overwrite``: a random run of up to 64 bytes replaced by random bytes;
- ``insert``: up to 64 random bytes inserted;
- ``inflate``: for zip containers, an entry's declared uncompressed size (local header
  and central directory) raised by up to 2⁴⁰, or an ``.npy`` shape in the clear raised;
  for text files a number replaced by a huge one.

Each input is read by its reader in a worker process that runs under an address-space
limit (``--memory-gib``, 1 GiB by default, ``RLIMIT_AS`` over the worker's own baseline)
and an alarm (``--timeout-s``, 30 s). Outcomes: ``ok`` (read), ``library error`` (a
``TerrawattError``: the wanted answer to a bad file), ``uncaught`` (any other exception —
a defect, listed), ``hang`` (the alarm fired — a defect). The table and the JSON
(``--out``) give the counts per reader and mutation, the peak memory of the workers and
the defects with their first messages.

Usage::

    python benchmarks/fuzz_readers.py --n 100000 --workers 2 --out out/fuzz.json    # the README figure
    python benchmarks/fuzz_readers.py --n 300 --out out/fuzz_quick.json             # the test suite's smoke run
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing as mp
import os
import platform
import random
import resource
import signal
import struct
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Any

FIXTURES = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "borealtc"
MUTATIONS = ("truncate", "flip", "overwrite", "insert", "inflate")


# ------------------------------------------------------------------ seeds and readers
def write_seeds(folder: Path) -> dict[str, Path]:
    """One small real file (or folder) per reader."""
    from energy import read_borealtc, write_csv_log
    from energy.models import LinearCurrentModel, fit_interval
    from terrain import procedural_map, write_geotiff

    from energy import VibrationCurrentEstimator
    from energy.models.config import estimator_preset

    logs = read_borealtc(FIXTURES)
    seeds = {"model": fit_interval(LinearCurrentModel(), logs, folds=2).save(folder / "model.zip")}
    tiny = estimator_preset("default").replace(hidden_sizes=(8,), n_members=2, max_epochs=2, patience=None)
    seeds["estimator_model"] = VibrationCurrentEstimator(tiny, seed=0).fit(logs).save(folder / "estimator.zip")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "energy"))
    from robot_bags import write_robot_bag  # the test suite's Husky-style ROS 1 bag writer

    write_robot_bag(folder / "husky.bag", duration_s=4.0)
    seeds["rosbag"] = folder / "husky.bag"
    tmap = procedural_map((24, 30), 1.0, seed=1)
    seeds["map"] = tmap.save(folder / "map.npz")
    seeds["csv_log"] = write_csv_log(logs[0], folder / "log.csv")
    seeds["borealtc_pro"] = next(FIXTURES.glob("*/pro_*.csv"))
    seeds["geotiff"] = write_geotiff(tmap, folder / "dem.tif")
    pairs = folder / "pairs.csv"
    pairs.write_text("name,start_x_m,start_y_m,goal_x_m,goal_y_m\na,2,2,20,20\nb,20,20,2,2\n")
    seeds["pairs"] = pairs
    return seeds


def _read(kind: str, path: Path) -> Any:
    """Read ``path`` with the reader of ``kind`` (the whole reading path a command takes)."""
    if kind == "rosbag":
        from energy import read_rosbag

        return read_rosbag(path, "/odometry/filtered", "/imu/data", "/status",
                           current_fields=("left_driver_current", "right_driver_current"),
                           voltage_field="battery_voltage", drive_clock="currents")
    if kind in ("model", "estimator_model"):
        from energy import load_current_model

        return load_current_model(path)
    if kind == "map":
        from terrain import TerrainMap

        return TerrainMap.load(path)
    if kind == "csv_log":
        from energy import read_csv_log

        return read_csv_log(path)
    if kind == "borealtc_pro":
        import shutil

        from energy import read_borealtc

        run = path.parent / "run"  # a one-run BorealTC folder: the mutated pro file beside its imu file
        ground = run / "FUZZ"
        ground.mkdir(parents=True, exist_ok=True)
        shutil.copy(path, ground / "pro_00.csv")
        shutil.copy(_SEEDS["borealtc_imu"], ground / "imu_00.csv")
        return read_borealtc(run)
    if kind == "geotiff":
        from terrain import read_geotiff

        return read_geotiff(path)
    if kind == "pairs":
        from planner import read_pairs_csv

        return read_pairs_csv(path)
    raise ValueError(kind)


# ------------------------------------------------------------------ mutations
def _zip_inflate(data: bytearray, rng: random.Random) -> bytearray:
    """Raise the declared uncompressed size of one entry (local header and central directory)."""
    huge = rng.choice([2**31 - 1, 2**32 - 1, 10**9, 3 * 2**30])
    for sig, off in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        starts = [i for i in range(len(data) - 4) if data[i:i + 4] == sig]
        if starts:
            i = rng.choice(starts)
            if i + off + 4 <= len(data):
                struct.pack_into("<I", data, i + off, huge & 0xFFFFFFFF)
    shape_at = data.find(b"'shape': (")
    if shape_at >= 0 and rng.random() < 0.5:  # an .npy header stored without compression
        end = data.find(b")", shape_at)
        data[shape_at + 10:end] = b"1099511627776,"
    return data


def mutate(seed: bytes, how: str, rng: random.Random, is_zip: bool) -> bytes:
    data = bytearray(seed)
    if how == "truncate":
        return bytes(data[: rng.randrange(0, max(len(data), 1))])
    if how == "flip":
        for _ in range(rng.randint(1, 16)):
            i = rng.randrange(len(data))
            data[i] ^= 1 << rng.randrange(8)
        return bytes(data)
    if how == "overwrite":
        i = rng.randrange(len(data))
        n = rng.randint(1, 64)
        data[i:i + n] = bytes(rng.randrange(256) for _ in range(n))
        return bytes(data)
    if how == "insert":
        i = rng.randrange(len(data) + 1)
        data[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
        return bytes(data)
    if is_zip:
        return bytes(_zip_inflate(data, rng))
    digits = [i for i in range(len(data)) if 48 <= data[i] <= 57]  # a number in the text: make it huge
    if digits:
        i = rng.choice(digits)
        data[i:i + 1] = b"9" * rng.randint(20, 400)
    return bytes(data)


# ------------------------------------------------------------------ workers
_SEEDS: dict[str, Path] = {}


def _init(seeds: dict[str, Path], memory_gib: float) -> None:
    _SEEDS.update(seeds)
    import warnings

    warnings.simplefilter("ignore")
    import energy  # noqa: F401  (imported before the limit: the baseline the limit is set over)
    import planner  # noqa: F401
    import terrain  # noqa: F401

    with open("/proc/self/statm") as fh:
        baseline = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    limit = baseline + int(memory_gib * 1024**3)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


class _Alarm(Exception):
    pass


def _on_alarm(signum: int, frame: Any) -> None:
    raise _Alarm()


def _one(task: tuple[int, str, str, int, float]) -> tuple[int, str, str, str, str]:
    from terrain import TerrawattError

    index, kind, how, seed, timeout_s = task
    rng = random.Random(seed)
    src = _SEEDS[kind]
    data = mutate(src.read_bytes(), how, rng, zipfile.is_zipfile(src))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"input{src.suffix}"
        path.write_bytes(data)
        signal.signal(signal.SIGALRM, _on_alarm)
        signal.setitimer(signal.ITIMER_REAL, timeout_s)
        try:
            _read(kind, path)
            outcome, detail = "ok", ""
        except _Alarm:
            outcome, detail = "hang", f"over {timeout_s:g} s"
        except TerrawattError as exc:
            outcome, detail = "library error", type(exc).__name__
        except BaseException as exc:  # noqa: BLE001 - a defect, recorded
            outcome, detail = "uncaught", f"{type(exc).__name__}: {str(exc)[:200]}"
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    return index, kind, how, outcome, detail


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000, help="mutated inputs (default 2000; the README figure: 100000)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--memory-gib", type=float, default=1.0, help="address-space allowance of a worker above its baseline")
    ap.add_argument("--timeout-s", type=float, default=30.0, help="a read longer than this is a hang")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("out/fuzz_readers.json"))
    args = ap.parse_args(argv)
    from terrawatt_base.atomic import write_json_atomic

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        seeds = write_seeds(Path(tmp))
        seeds["borealtc_imu"] = next(FIXTURES.glob("*/imu_*.csv"))
        kinds = [k for k in seeds if k != "borealtc_imu"]
        rng = random.Random(args.seed)
        tasks = [(i, kinds[i % len(kinds)], rng.choice(MUTATIONS), rng.randrange(2**31), args.timeout_s)
                 for i in range(args.n)]
        ctx = mp.get_context("fork")
        with ctx.Pool(args.workers, initializer=_init, initargs=(seeds, args.memory_gib), maxtasksperchild=500) as pool:
            results = list(pool.imap_unordered(_one, tasks, chunksize=20))
    wall = time.perf_counter() - t0
    peak_gib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024 / 1024**3
    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    defects = []
    for _, kind, how, outcome, detail in results:
        counts[kind][outcome] += 1
        counts["all"][outcome] += 1
        if outcome in ("uncaught", "hang"):
            defects.append({"reader": kind, "mutation": how, "outcome": outcome, "detail": detail})
    print(f"{'reader':<14}{'inputs':>8}{'ok':>8}{'library error':>15}{'uncaught':>10}{'hang':>6}")
    for kind, c in counts.items():
        print(f"{kind:<14}{sum(c.values()):>8}{c['ok']:>8}{c['library error']:>15}{c['uncaught']:>10}{c['hang']:>6}")
    print(f"\n{args.n} inputs in {wall:.1f} s on {args.workers} workers; peak worker memory {peak_gib:.2f} GiB "
          f"(limit {args.memory_gib:g} GiB above each worker's baseline)")
    for d in collections.Counter((d["reader"], d["detail"][:90]) for d in defects).most_common(12):
        print("  defect:", d)
    write_json_atomic(args.out, {
        "benchmark": "fuzz_readers", "n": args.n, "workers": args.workers, "memory_gib": args.memory_gib,
        "timeout_s": args.timeout_s, "seed": args.seed, "wall_s": wall, "peak_worker_gib": peak_gib,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "platform": sys.platform},
        "counts": {k: dict(v) for k, v in counts.items()}, "defects": defects[:500], "n_defects": len(defects),
    })
    print(f"wrote {args.out}")
    return 0 if not defects else 1


if __name__ == "__main__":
    raise SystemExit(main())
