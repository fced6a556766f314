"""Fuzz every reader with mutated real files: a clear library error or a correct result, never a crash or a hang.

Seed files are written first (a current-model file with an interval, an estimator file
with network weights, a map ``.npz``, a CSV log, a BorealTC run folder, a GeoTIFF DEM, a
Husky-style ROS 1 bag, a pairs CSV, a robot file, a CSV log with its column layout, a
land-cover classes file, and a linear model with a two-ground forecast interval). Each
input is one seed mutated in one of these ways:

- ``truncate``: cut at a random length;
- ``flip``: 1-16 random bit flips;
- ``overwrite``: a random run of up to 64 bytes replaced by random bytes;
- ``insert``: up to 64 random bytes inserted;
- ``inflate``: for zip containers, an entry's declared uncompressed size (local header
  and central directory) raised by up to 2⁴⁰, or an ``.npy`` shape in the clear raised;
  for text files a number replaced by a huge one (20-400 digits, or past Python's
  4300-digit limit of ``int()``);
- ``rewrite`` (the interval model only): the zip re-written with valid CRCs and one value
  of its forecast-interval block changed (a covariance negated, scaled by 1e30, made
  asymmetric or non-finite, re-shaped, re-typed; a scalar replaced; a key dropped, a
  ground renamed, an array reference broken), so the interval checks themselves are met.

The CSV-layout seed is a bundle: the layout as the command line gives it (``columns``,
``units`` and ``rates`` lines of ``FIELD=VALUE`` words, as ``--csv-columns``,
``--csv-units``, ``--csv-rates``), :data:`LAYOUT_SEPARATOR`, then the CSV log; a mutation
alters the layout, the CSV or both.

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
import io
import json
import multiprocessing as mp
import os
import platform
import random
import re
import resource
import signal
import struct
import sys
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

FIXTURES = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "borealtc"
TEST_SAMPLES = Path(__file__).resolve().parents[1] / "tests" / "energy"  # robot_bags, interval_samples
MUTATIONS = ("truncate", "flip", "overwrite", "insert", "inflate")
#: Mutations of a kind beyond :data:`MUTATIONS`.
EXTRA_MUTATIONS = {"interval_model": ("rewrite",)}
#: Between the layout text and the CSV log of a ``csv_layout`` input.
LAYOUT_SEPARATOR = b"\n--- csv ---\n"
#: The land-cover classes seed: ESA WorldCover codes, as ``read_landcover_classes`` documents them.
LANDCOVER_CLASSES = """# ESA WorldCover 2021 -> terrawatt grounds
code,ground,label
10,obstacle,Tree cover
20,gravel,Shrubland
30,grass,Grassland
50,asphalt,Built-up
60,gravel,Bare / sparse vegetation
70,unknown,Snow and ice
80,obstacle,Permanent water bodies
"""


# ------------------------------------------------------------------ seeds and readers
def write_seeds(folder: Path) -> dict[str, Path]:
    """One small real file (or folder) per reader."""
    from energy import VibrationCurrentEstimator, read_borealtc, robot_preset, write_csv_log
    from energy.models import LinearCurrentModel, fit_interval
    from energy.models.config import estimator_preset
    from energy.params import write_robot_file
    from terrain import procedural_map, write_geotiff

    logs = read_borealtc(FIXTURES)
    seeds = {"model": fit_interval(LinearCurrentModel(), logs, folds=2).save(folder / "model.zip")}
    tiny = estimator_preset("default").replace(hidden_sizes=(8,), n_members=2, max_epochs=2, patience=None)
    seeds["estimator_model"] = VibrationCurrentEstimator(tiny, seed=0).fit(logs).save(folder / "estimator.zip")
    sys.path.insert(0, str(TEST_SAMPLES))
    from interval_samples import interval_log  # the test suite's runs of known currents
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
    seeds["robot"] = write_robot_file(robot_preset("husky"), folder / "robot.json")
    csv = write_csv_log(interval_log(7, "sand", duration_s=3.0), folder / "layout_log.csv")
    layout = ("columns time=time_s v=v_mps omega=omega_radps current_left=current_left_a "
              "current_right=current_right_a accel_z=accel_z_mps2\n"
              "units time=s current_left=A current_right=A accel_z=m/s^2\n"
              "rates mixed\n")
    seeds["csv_layout"] = folder / "layout.txt"
    seeds["csv_layout"].write_bytes(join_layout_bundle(layout.encode(), csv.read_bytes()))
    seeds["landcover_classes"] = folder / "classes.csv"
    seeds["landcover_classes"].write_text(LANDCOVER_CLASSES, encoding="utf-8")
    runs = [interval_log(s, "a", offset_a=0.3 * s, duration_s=10.0) for s in range(3)]  # two grounds: per-ground
    runs += [interval_log(10 + s, "b", gain=1.3, duration_s=10.0) for s in range(3)]  # and new-ground covariances
    seeds["interval_model"] = fit_interval(LinearCurrentModel(), runs, folds=3).save(folder / "interval_model.zip")
    return seeds


def join_layout_bundle(layout: bytes, csv: bytes) -> bytes:
    """A ``csv_layout`` input: the layout text, :data:`LAYOUT_SEPARATOR`, the CSV log."""
    return layout + LAYOUT_SEPARATOR + csv


def split_layout_bundle(data: bytes) -> tuple[bytes, bytes]:
    """(layout text, CSV log) of a ``csv_layout`` input; without a separator, all layout."""
    layout, _, csv = data.partition(LAYOUT_SEPARATOR)
    return layout, csv


def read_layout_text(text: str) -> dict[str, Any]:
    """The :class:`energy.io.CsvLayout` arguments of a layout text, as the command line parses its flags.

    Each line is a flag name (``columns``, ``units`` or ``rates``) and its words: ``FIELD=VALUE``
    words, each field once (``--csv-columns``, ``--csv-units``), or one choice (``--csv-rates``).
    What the command line would refuse raises the ``InvalidParameterError`` it raises.
    """
    from terrawatt_base.errors import InvalidParameterError

    out: dict[str, Any] = {}
    for line in text.splitlines():
        words = line.split()
        if not words:
            continue
        flag, values = words[0], words[1:]
        if flag not in ("columns", "units", "rates") or flag in out or not values:
            raise InvalidParameterError(f"layout line {line!r:.80}: expected 'columns', 'units' or 'rates' once, "
                                        "with values")
        if flag == "rates":
            if len(values) != 1:
                raise InvalidParameterError(f"--csv-rates takes one value, got {values!r:.80}")
            out["rates"] = values[0]
            continue
        pairs: dict[str, str] = {}
        for word in values:  # as terrawatt_cli.data parses --csv-columns / --csv-units
            key, sep, value = word.partition("=")
            if not sep or not key or not value or key in pairs:
                raise InvalidParameterError(f"--csv-{flag} takes FIELD=VALUE words, each field once; got {word!r}")
            pairs[key] = value
        out[flag] = pairs
    return out


def _read(kind: str, path: Path) -> Any:
    """Read ``path`` with the reader of ``kind`` (the whole reading path a command takes)."""
    if kind == "rosbag":
        from energy import BagTopics, read_rosbag

        return read_rosbag(path, BagTopics("/odometry/filtered", "/imu/data", "/status",
                                           current_fields=("left_driver_current", "right_driver_current"),
                                           voltage_field="battery_voltage", drive_clock="currents"))
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
    if kind == "robot":
        from energy.params import robot_params

        return robot_params(path, name="--robot")  # as --robot FILE.json
    if kind == "csv_layout":
        from energy.io import CsvLayout

        layout, csv = split_layout_bundle(path.read_bytes())
        csv_path = path.with_name("log.csv")
        csv_path.write_bytes(csv)
        # argv reaches Python decoded with surrogateescape: any bytes make a str
        return CsvLayout(**read_layout_text(layout.decode("utf-8", "surrogateescape"))).read(csv_path)
    if kind == "landcover_classes":
        from terrain import read_landcover_classes

        return read_landcover_classes(path)
    if kind == "interval_model":
        from energy import load_current_model

        return load_current_model(path)
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


def _rewrite_array(arr: np.ndarray, rng: random.Random) -> np.ndarray:
    """``arr`` made wrong in one way a covariance or spread can be wrong."""
    a = np.array(arr, dtype=np.float64)
    how = rng.choice(["negate", "scale", "nonfinite", "asymmetric", "diagonal", "reshape", "dtype", "empty", "tiny"])
    if how == "negate":
        return -a
    if how == "scale":
        return a * rng.choice([1e30, 1e6, 1e300, -1.0, 0.0])
    if how == "tiny":
        return a * 1e-300
    flat = a.reshape(-1)
    if flat.size and how == "nonfinite":
        flat[rng.randrange(flat.size)] = rng.choice([np.nan, np.inf, -np.inf])
        return a
    if a.ndim == 3 and a.shape[-1] > 1 and how in ("asymmetric", "diagonal"):
        s, i = rng.randrange(a.shape[0]), rng.randrange(a.shape[-1])
        if how == "diagonal":
            a[s, i, i] = -rng.choice([1e-12, 1e-3, 1.0, 1e6])
        else:
            a[s, i, (i + 1) % a.shape[-1]] += rng.choice([1e-6, 1.0, 1e3])
        return a
    if how == "dtype":
        return a.astype(rng.choice([np.float32, np.int64, np.uint8, np.float16]))
    if how == "empty":
        return np.zeros((0,) + a.shape[1:])
    return rng.choice([a.reshape(-1), a[..., :-1], a[None], a.T.copy(), np.zeros((2, 4, 4)), np.zeros((2, 3))])


_SCALARS = [0, -1, 1e-300, 1e308, float("nan"), float("inf"), 10**30, 10**400, "text", None, [], {}, True, 1.5,
            [[1.0]], {"__array__": "arrays/0.npy"}]


def rewrite_interval(seed: bytes, rng: random.Random) -> bytes:
    """A model file re-written (valid CRCs) with one value of its forecast-interval block changed."""
    with zipfile.ZipFile(io.BytesIO(seed)) as archive:
        entries = {i.filename: archive.read(i) for i in archive.infolist()}
    doc = json.loads(entries["model.json"])
    block = doc["interval"]
    refs = [(block, k) for k, v in block.items() if isinstance(v, dict) and "__array__" in v]
    refs += [(block["run_cov"], g) for g in block["run_cov"]]
    scalars = [(block, k) for k, v in block.items() if not isinstance(v, dict)]
    how = rng.choice(["array", "array", "array", "scalar", "drop", "ground", "reference", "container"])
    if how == "array":
        parent, key = rng.choice(refs)
        name = parent[key]["__array__"]
        buf = io.BytesIO()
        np.save(buf, _rewrite_array(np.load(io.BytesIO(entries[name])), rng), allow_pickle=False)
        entries[name] = buf.getvalue()
    elif how == "scalar":
        parent, key = rng.choice(scalars + refs)
        parent[key] = rng.choice(_SCALARS)
    elif how == "drop":
        parent, key = rng.choice([(block, k) for k in block] + [(block["run_cov"], g) for g in block["run_cov"]])
        del parent[key]
    elif how == "ground":
        runs = block["run_cov"]
        old = rng.choice(sorted(runs))
        runs[rng.choice(["", "*", "a", "b", "x" * 300, "\u0000", "c"])] = runs.pop(old)
    elif how == "reference":
        parent, key = rng.choice(refs)
        parent[key] = {"__array__": rng.choice(["arrays/99.npy", "model.json", "", 3, None, "../arrays/0.npy"])}
    else:
        doc["interval"] = rng.choice([None, [], "interval", 1.0, {}, {"run_cov": {}}, block["run_cov"]])
    entries["model.json"] = json.dumps(doc, indent=1).encode()
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for n, b in entries.items():
            archive.writestr(n, b)
    return out.getvalue()


def mutations_of(kind: str) -> tuple[str, ...]:
    """The mutations drawn for an input of ``kind``."""
    return MUTATIONS + EXTRA_MUTATIONS.get(kind, ())


def mutate_input(kind: str, seed: bytes, how: str, rng: random.Random, is_zip: bool) -> bytes:
    """``seed`` of ``kind`` mutated: a ``csv_layout`` bundle in its layout, its CSV or both; an interval model
    ``rewrite`` in its interval block; anything else as :func:`mutate`."""
    if how == "rewrite":
        return rewrite_interval(seed, rng)
    if kind == "csv_layout":
        parts = list(split_layout_bundle(seed))
        for i in rng.choice([(0,), (1,), (0, 1)]):
            parts[i] = mutate(parts[i], how, rng, False)
        return join_layout_bundle(*parts)
    return mutate(seed, how, rng, is_zip)


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
        data[i:i + 1] = b"9" * (rng.randint(20, 400) if rng.random() < 0.75 else rng.randint(4301, 6000))
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
    data = mutate_input(kind, src.read_bytes(), how, rng, zipfile.is_zipfile(src))
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
        tasks = [(i, kinds[i % len(kinds)], rng.choice(mutations_of(kinds[i % len(kinds)])), rng.randrange(2**31),
                  args.timeout_s) for i in range(args.n)]
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
    print(f"{'reader':<18}{'inputs':>8}{'ok':>8}{'library error':>15}{'uncaught':>10}{'hang':>6}")
    for kind, c in counts.items():
        print(f"{kind:<18}{sum(c.values()):>8}{c['ok']:>8}{c['library error']:>15}{c['uncaught']:>10}{c['hang']:>6}")
    print(f"\n{args.n} inputs in {wall:.1f} s on {args.workers} workers; peak worker memory {peak_gib:.2f} GiB "
          f"(limit {args.memory_gib:g} GiB above each worker's baseline)")
    for d in collections.Counter((d["reader"], re.sub(r"\d+", "N", d["detail"][:90])) for d in defects).most_common(12):
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
