"""Every reader, property-based: a mutated real file gives a library error or a correct result, within a memory cap.

Hypothesis draws the mutation of one real seed file per reader (the seeds of
``benchmarks/fuzz_readers.py``: model and estimator files, a map ``.npz``, a CSV log, a
BorealTC run, a GeoTIFF, a ROS 1 bag, a pairs CSV): a truncation, bit flips, an overwritten
or inserted run of bytes, an inflated header (a zip entry's declared size, an ``.npy``
shape, a huge number in a text file) and, for the zip containers, an array entry re-saved
with a wrong dtype (complex, bool, text) under a valid CRC. Each input is read in a forked
child under an address-space limit of 1 GiB above the child's baseline and a 30 s alarm.

The property: the child ends in a ``TerrawattError`` or with a result of the reader's
type; for the zip containers, whose entries are CRC-checked, an accepted file must read
exactly as the seed (nothing silently altered); a re-typed array entry must be refused.
"""

from __future__ import annotations

import importlib.util
import io
import os
import pickle
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
_ZIP_KINDS = ("model", "estimator_model", "map")
_KINDS = ("model", "estimator_model", "map", "csv_log", "borealtc_pro", "geotiff", "rosbag", "pairs")
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
    bench = _bench()
    folder = tmp_path_factory.mktemp("seeds")
    files = bench.write_seeds(folder)
    files["borealtc_imu"] = next(bench.FIXTURES.glob("*/imu_*.csv"))
    bench._SEEDS.update(files)  # the BorealTC reader pairs the mutated pro file with this imu file
    reference = {k: _fingerprint(k, bench._read(k, files[k])) for k in _ZIP_KINDS}
    return bench, files, reference


def _fingerprint(kind: str, result) -> bytes:
    """What a zip container's content reads as, to compare an accepted mutated file with its seed."""
    if kind == "map":
        return pickle.dumps(({name: np.asarray(result[name]).tobytes() for name in result.keys()}, result.ground_names))
    record = result.to_record()
    return pickle.dumps((record.model_class, repr(record.params), repr(record.state)))


_TYPES = {"model": "CurrentModel", "estimator_model": "CurrentModel", "map": "TerrainMap", "csv_log": "InteractionLog",
          "borealtc_pro": "list", "geotiff": "TerrainMap", "rosbag": "InteractionLog", "pairs": "BatchPairs"}


def _read_capped(bench, kind: str, path: Path) -> tuple[str, str, bytes | None]:
    """Read ``path`` in a forked child under the memory cap and the alarm: (outcome, detail, fingerprint)."""
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
                if _TYPES[kind] not in names:
                    outcome = ("wrong type", type(result).__name__, None)
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


@st.composite
def mutations(draw, kind: str, seed: bytes):
    is_zip = kind in _ZIP_KINDS
    how = draw(st.sampled_from(["truncate", "flip", "overwrite", "insert", "inflate", *(["retype"] if is_zip else [])]))
    if how == "inflate":
        return how, _inflate(draw, seed, is_zip)
    if how == "retype":
        return how, _retype(draw, seed)
    return how, {"truncate": _truncate, "flip": _flip, "overwrite": _overwrite, "insert": _insert}[how](draw, seed)


@pytest.mark.parametrize("kind", _KINDS)
def test_a_mutated_file_gives_a_library_error_or_the_right_result_within_a_memory_cap(kind, seeds, tmp_path):
    bench, files, reference = seeds
    seed = files[kind].read_bytes()
    path = tmp_path / f"input{files[kind].suffix}"
    seen = set()

    @_SETTINGS
    @given(mutation=mutations(kind, seed))
    def check(mutation):
        how, data = mutation
        path.write_bytes(data)
        outcome, detail, fingerprint = _read_capped(bench, kind, path)
        seen.add(outcome)
        assert outcome in ("ok", "library error"), f"{kind}, {how}: {outcome} {detail}"
        if kind in _ZIP_KINDS and outcome == "ok":
            assert fingerprint == reference[kind], f"{kind}, {how}: an accepted file reads differently from its seed"
            assert how != "retype", f"{kind}: an array entry of the wrong dtype was accepted"

    check()
    assert "library error" in seen  # the mutations do reach the readers' checks
