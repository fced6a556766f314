"""Every reader, property-based: a mutated real file gives a library error or a correct result, within a memory cap.

Hypothesis draws the mutation of one real seed file per reader (the seeds of
``benchmarks/fuzz_readers.py``: model and estimator files, a map ``.npz``, a CSV log, a
BorealTC run, a GeoTIFF, a ROS 1 bag, a pairs CSV, a robot file, a CSV log with its column
layout, a land-cover classes file, a model with a two-ground forecast interval): a
truncation, bit flips, an overwritten or inserted run of bytes, an inflated header (a zip
entry's declared size, an ``.npy`` shape, a huge number in a text file) and, for the zip
containers, an array entry re-saved with a wrong dtype (complex, bool, text) under a valid
CRC. The CSV-layout input mutates its layout text, its CSV or both; the interval model is
also re-written under valid CRCs with one value of its interval block made wrong
(``rewrite``). Each input is read in a forked child under an address-space limit of 1 GiB
above the child's baseline and a 30 s alarm.

The property: the child ends in a ``TerrawattError`` or with a result of the reader's
type; for the zip containers, whose entries are CRC-checked, an accepted file must read
exactly as the seed (nothing silently altered); a re-typed array entry must be refused; a
re-written interval that is accepted must still forecast finite, non-negative spreads.
A number past Python's 4300-digit ``int()`` limit (each of the first numbers of each text
seed in turn) is its own deterministic test.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import io
import os
import pickle
import random
import re
import resource
import signal
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="the readers run in forked children under RLIMIT_AS")

_BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "fuzz_readers.py"
MEMORY_CAP_BYTES = 1 << 30
TIMEOUT_S = 30
_ZIP_KINDS = ("model", "estimator_model", "map", "interval_model")
_KINDS = ("model", "estimator_model", "map", "csv_log", "borealtc_pro", "geotiff", "rosbag", "pairs", "robot",
          "csv_layout", "landcover_classes", "interval_model")
_TEXT_KINDS = ("csv_log", "borealtc_pro", "pairs", "robot", "csv_layout", "landcover_classes")
_SETTINGS = settings(max_examples=25, deadline=None, derandomize=True, database=None,
                     suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _bench():
    spec = importlib.util.spec_from_file_location("fuzz_readers", _BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    pytest.importorskip("rasterio", reason="the GeoTIFF seed needs the geo extra")
    pytest.importorskip("rosbags", reason="the bag seed needs the ros extra")
    import planner  # noqa: F401  (imported once here, not in every forked child)

    bench = _bench()
    folder = tmp_path_factory.mktemp("seeds")
    files = bench.write_seeds(folder)
    files["borealtc_imu"] = next(bench.FIXTURES.glob("*/imu_*.csv"))
    bench._SEEDS.update(files)  # the BorealTC reader pairs the mutated pro file with this imu file
    reference = {k: _fingerprint(k, bench._read(k, files[k])) for k in _ZIP_KINDS}
    for kind in _KINDS:  # every seed reads, as the reader's type (a copy: the BorealTC reader builds a run beside it)
        copy = tmp_path_factory.mktemp(kind) / f"input{files[kind].suffix}"
        copy.write_bytes(files[kind].read_bytes())
        assert _TYPES[kind] in {c.__name__ for c in type(bench._read(kind, copy)).__mro__}, kind
    return bench, files, reference


@pytest.fixture(scope="module")
def probe_logs(seeds):
    """A run of a ground the interval model knows and the same run on a ground it does not."""
    bench = seeds[0]
    if str(bench.TEST_SAMPLES) not in sys.path:
        sys.path.insert(0, str(bench.TEST_SAMPLES))
    from interval_samples import interval_log  # the samples the seed was fitted on

    known = interval_log(99, "a", duration_s=5.0)
    return known, dataclasses.replace(known, meta=dataclasses.replace(known.meta, ground_label="unseen"))


def _plain(value):
    """A record's content with every array as (dtype, shape, bytes): equal exactly when the content is."""
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, dict):
        return sorted((str(k), _plain(v)) for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return repr(value)


def _fingerprint(kind: str, result) -> bytes:
    """What a zip container's content reads as, to compare an accepted mutated file with its seed."""
    if kind == "map":
        return pickle.dumps(({name: np.asarray(result[name]).tobytes() for name in result.keys()}, result.ground_names))
    record = result.to_record()
    return pickle.dumps((record.model_class, repr(record.params), repr(record.state), _plain(record.interval),
                         _plain(record.trained_on)))


def _wrong_forecast(model, logs) -> str:
    """What is wrong with the forecasts of an accepted interval model (empty: nothing)."""
    for log in logs:
        forecast = model.predict_distribution(log)
        charge = forecast.charge()
        parts = {"mean_a": forecast.mean_a, "run_sd_a": forecast.run_sd_a, "total_sd_as": charge.total_sd_as}
        for name, value in parts.items():
            value = np.asarray(value, dtype=np.float64)
            if not np.all(np.isfinite(value)) or (name != "mean_a" and np.any(value < 0)):
                return f"ground {log.meta.ground_label!r}: {name} {value.ravel()[:4]!r}"
    return ""


_TYPES = {"model": "CurrentModel", "estimator_model": "CurrentModel", "map": "TerrainMap", "csv_log": "InteractionLog",
          "borealtc_pro": "list", "geotiff": "TerrainMap", "rosbag": "InteractionLog", "pairs": "BatchPairs",
          "robot": "RobotParams", "csv_layout": "InteractionLog", "landcover_classes": "LandcoverClasses",
          "interval_model": "CurrentModel"}


def _read_capped(bench, kind: str, path: Path, probes=()) -> tuple[str, str, bytes | None]:
    """Read ``path`` in a forked child under the memory cap and the alarm: (outcome, detail, fingerprint); an
    accepted interval model forecasts ``probes`` too (``wrong result`` if a spread is not finite and >= 0)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        os.close(r)
        code = 0
        try:
            with open("/proc/self/statm") as fh:
                baseline = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
            resource.setrlimit(resource.RLIMIT_AS, (baseline + MEMORY_CAP_BYTES, baseline + MEMORY_CAP_BYTES))
            signal.alarm(TIMEOUT_S)
            from terrain import TerrawattError

            try:
                result = bench._read(kind, path)
                names = {type(result).__name__, *(c.__name__ for c in type(result).__mro__)}
                outcome = ("ok", "", _fingerprint(kind, result) if kind in _ZIP_KINDS else None)
                wrong = _wrong_forecast(result, probes) if kind == "interval_model" and _TYPES[kind] in names else ""
                if _TYPES[kind] not in names:
                    outcome = ("wrong type", type(result).__name__, None)
                elif wrong:
                    outcome = ("wrong result", wrong, None)
            except TerrawattError as exc:
                outcome = ("library error", f"{type(exc).__name__}: {str(exc)[:300]}", None)
            except BaseException as exc:  # noqa: BLE001 - the defect this test looks for
                outcome = ("uncaught", f"{type(exc).__name__}: {str(exc)[:300]}", None)
            os.write(w, pickle.dumps(outcome))
        except BaseException:  # noqa: BLE001
            code = 1
        finally:
            os._exit(code)
    os.close(w)
    with os.fdopen(r, "rb") as fh:
        data = fh.read()
    _, status = os.waitpid(pid, 0)
    if not data:
        sig = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
        return ("hang" if sig == signal.SIGALRM else "crash", f"status {status}", None)
    return pickle.loads(data)


# ------------------------------------------------------------------ mutations, drawn by hypothesis
def _truncate(draw, data: bytes) -> bytes:
    return data[: draw(st.integers(0, max(len(data) - 1, 0)))]


def _flip(draw, data: bytes) -> bytes:
    out = bytearray(data)
    for pos, bit in draw(st.lists(st.tuples(st.integers(0, len(data) - 1), st.integers(0, 7)), min_size=1, max_size=16)):
        out[pos] ^= 1 << bit
    return bytes(out)


def _overwrite(draw, data: bytes) -> bytes:
    pos = draw(st.integers(0, len(data) - 1))
    junk = draw(st.binary(min_size=1, max_size=64))
    return data[:pos] + junk + data[pos + len(junk):]


def _insert(draw, data: bytes) -> bytes:
    pos = draw(st.integers(0, len(data)))
    return data[:pos] + draw(st.binary(min_size=1, max_size=64)) + data[pos:]


def _inflate(draw, data: bytes, is_zip: bool) -> bytes:
    out = bytearray(data)
    if is_zip:  # an entry's declared uncompressed size, in its local header and the central directory
        huge = draw(st.sampled_from([2**31 - 1, 2**32 - 1, 10**9, 3 * 2**30]))
        for sig, off in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
            starts = [i for i in range(len(out) - 4) if out[i:i + 4] == sig]
            i = draw(st.sampled_from(starts))
            out[i + off:i + off + 4] = huge.to_bytes(4, "little")
        return bytes(out)
    digits = [i for i, b in enumerate(out) if 48 <= b <= 57]
    i = draw(st.sampled_from(digits))
    out[i:i + 1] = b"9" * draw(st.integers(20, 400))
    return bytes(out)


def _retype(draw, data: bytes) -> bytes:
    """An ``.npy`` entry of the zip re-saved with a wrong dtype, its CRC valid: only the reader's dtype checks can refuse it."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        entries = {i.filename: archive.read(i) for i in archive.infolist()}
    arrays = sorted(n for n, b in entries.items() if n.endswith(".npy") and np.load(io.BytesIO(b)).dtype.kind == "f")
    name = draw(st.sampled_from(arrays))
    arr = np.load(io.BytesIO(entries[name]))
    kind = draw(st.sampled_from(["complex", "bool", "text"]))
    new = {"complex": arr.astype(np.complex128) + 1j, "bool": arr > 0, "text": arr.astype(str)}[kind]
    buf = io.BytesIO()
    np.save(buf, new, allow_pickle=False)
    entries[name] = buf.getvalue()
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for n, b in entries.items():
            archive.writestr(n, b)
    return out.getvalue()


def _mutate(draw, how: str, data: bytes, is_zip: bool) -> bytes:
    if how == "inflate":
        return _inflate(draw, data, is_zip)
    if how == "retype":
        return _retype(draw, data)
    return {"truncate": _truncate, "flip": _flip, "overwrite": _overwrite, "insert": _insert}[how](draw, data)


@st.composite
def mutations(draw, kind: str, seed: bytes, bench):
    is_zip = kind in _ZIP_KINDS
    hows = ["truncate", "flip", "overwrite", "insert", "inflate", *(["retype"] if is_zip else [])]
    how = draw(st.sampled_from(hows + (["rewrite"] * 2 if kind == "interval_model" else [])))
    if how == "rewrite":  # the interval block re-written under valid CRCs (the benchmark's edits, drawn by seed)
        return how, bench.rewrite_interval(seed, random.Random(draw(st.integers(0, 2**32 - 1))))
    if kind == "csv_layout":  # the layout text, the CSV log or both
        parts = list(bench.split_layout_bundle(seed))
        where = draw(st.sampled_from(["layout", "csv", "both"]))
        for i in {"layout": (0,), "csv": (1,), "both": (0, 1)}[where]:
            parts[i] = _mutate(draw, how, parts[i], False)
        return f"{how} ({where})", bench.join_layout_bundle(*parts)
    return how, _mutate(draw, how, seed, is_zip)


@pytest.mark.parametrize("kind", _KINDS)
def test_a_mutated_file_gives_a_library_error_or_the_right_result_within_a_memory_cap(kind, seeds, probe_logs,
                                                                                    tmp_path):
    bench, files, reference = seeds
    seed = files[kind].read_bytes()
    path = tmp_path / f"input{files[kind].suffix}"
    seen = set()

    @_SETTINGS
    @given(mutation=mutations(kind, seed, bench))
    def check(mutation):
        how, data = mutation
        path.write_bytes(data)
        outcome, detail, fingerprint = _read_capped(bench, kind, path, probe_logs)
        seen.add(outcome)
        assert outcome in ("ok", "library error"), f"{kind}, {how}: {outcome} {detail}"
        if kind in _ZIP_KINDS and outcome == "ok" and how != "rewrite":  # a rewrite changes the content on purpose
            assert fingerprint == reference[kind], f"{kind}, {how}: an accepted file reads differently from its seed"
            assert how != "retype", f"{kind}: an array entry of the wrong dtype was accepted"

    check()
    assert "library error" in seen  # the mutations do reach the readers' checks


@pytest.mark.parametrize("kind", _TEXT_KINDS)
def test_a_number_past_pythons_int_digit_limit_gives_a_library_error_or_the_right_result(kind, seeds, tmp_path):
    """Each of the first 24 numbers of the file (its header and first rows) in turn made 5000 digits long."""
    bench, files, _ = seeds
    seed = files[kind].read_bytes()
    path = tmp_path / f"input{files[kind].suffix}"
    failures = []
    for match in list(re.finditer(rb"[0-9]+", seed))[:24]:
        path.write_bytes(seed[:match.start()] + b"9" * 5000 + seed[match.end():])
        outcome, detail, _ = _read_capped(bench, kind, path)
        if outcome not in ("ok", "library error"):
            failures.append(f"byte {match.start()}: {outcome} {detail[:120]}")
    assert not failures, failures
