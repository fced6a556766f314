"""Tests of terrawatt_base.containers: zip / .npz / .npy content checked before it is trusted."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from energy import LinearCurrentModel, load_current_model
from energy.io import BagTopics, read_borealtc
from terrain import FileFormatError, TerrainMap
from terrawatt_base.containers import load_npy, read_npz

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=False)
    return buf.getvalue()


def _rewrite(src: Path, dst: Path, replace: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(dst, "w", compression=zipfile.ZIP_DEFLATED) as b:
        names = a.namelist()
        for name in names:
            b.writestr(name, replace.get(name, a.read(name)))
        for name in set(replace) - set(names):
            b.writestr(name, replace[name])
    return dst


def test_an_npy_header_declaring_a_huge_shape_is_refused_before_allocating():
    data = _npy(np.zeros(4))
    forged = data.replace(b"(4,)", b"(1099511627776,)")  # 2**40 elements over a few bytes
    with pytest.raises(FileFormatError, match=r"declares shape \(1099511627776,\) of float64 \(8796093022208 bytes\) but holds"):
        load_npy(forged, "f", "entry 'x'")
    assert np.array_equal(load_npy(data, "f", "x"), np.zeros(4))


def test_an_npy_with_python_objects_is_refused():
    buf = io.BytesIO()
    np.save(buf, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(FileFormatError, match="never loads pickles"):
        load_npy(buf.getvalue(), "f", "x")


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("m") / "lin.zip"
    return LinearCurrentModel().fit(read_borealtc(FIXTURES)).save(path)


def test_a_model_file_over_the_memory_budget_is_refused_before_inflating(model_file, tmp_path, monkeypatch):
    with zipfile.ZipFile(model_file) as a:
        header = json.loads(a.read("model.json"))
    big = _rewrite(model_file, tmp_path / "big.zip", {"arrays/99.npy": _npy(np.zeros(2_000_000))})  # 16 MB of zeros
    assert big.stat().st_size < 200_000  # a small file that inflates 100 times
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", str(4_000_000))
    with pytest.raises(FileFormatError, match="more than the memory budget"):
        load_current_model(big)
    assert header["format"] == "terrawatt-current-model"


def test_a_corrupt_deflate_stream_is_a_file_format_error(model_file, tmp_path):
    raw = bytearray(model_file.read_bytes())
    with zipfile.ZipFile(model_file) as a:
        info = a.getinfo("model.json")
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    for k in range(start + 2, start + min(info.compress_size, 40)):
        raw[k] ^= 0xFF
    bad = tmp_path / "bad.zip"
    bad.write_bytes(bytes(raw))
    with pytest.raises(FileFormatError, match="bad.zip"):
        load_current_model(bad)


def test_a_map_whose_version_is_inf_is_a_file_format_error(tmp_path):
    good = TerrainMap(np.zeros((4, 5)), 1.0).save(tmp_path / "m.npz")
    content = read_npz(good, "map")
    content["__version__"] = np.array(np.inf)
    forged = tmp_path / "inf.npz"
    np.savez_compressed(forged, **content)
    with pytest.raises(FileFormatError, match="no valid format version"):
        TerrainMap.load(forged)


def test_nan_network_weights_do_not_load(tmp_path):
    from energy import VibrationCurrentEstimator
    from energy.models.config import estimator_preset

    cfg = estimator_preset("default").replace(hidden_sizes=(4,), n_members=1, max_epochs=1, patience=None,
                                              validation_fraction=0.0, physics_prior=None)
    path = VibrationCurrentEstimator(cfg, seed=0).fit(read_borealtc(FIXTURES)).save(tmp_path / "e.zip")
    with zipfile.ZipFile(path) as a:
        header = json.loads(a.read("model.json"))
    ref = header["state"]["weights"][0]
    entry = next(iter(ref.values()))["__array__"]
    with zipfile.ZipFile(path) as a:
        arr = np.load(io.BytesIO(a.read(entry)))
    arr = np.full_like(arr, np.nan)
    bad = _rewrite(path, tmp_path / "nan.zip", {entry: _npy(arr)})
    with pytest.raises(FileFormatError, match="non-finite"):
        load_current_model(bad)


@pytest.mark.parametrize(("array", "word"), [(np.ones(3) + 1j, "complex"), (np.ones(3) > 0, "bool"),
                                             (np.array(["1.5", "2"]), "text")])
def test_an_npy_entry_of_a_kind_not_asked_for_is_refused(array, word):
    buf = io.BytesIO()
    np.save(buf, array)
    assert load_npy(buf.getvalue(), "f", "x").dtype == array.dtype  # no restriction asked
    with pytest.raises(FileFormatError, match=rf"'f': x holds {word} values .* expected integer or unsigned"):
        load_npy(buf.getvalue(), "'f'", "x", kinds="iuf")


def test_a_csv_log_or_a_bag_over_the_memory_budget_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from energy import read_csv_log, read_rosbag
    from energy.io.bag_messages import BAG_MESSAGE_BYTES

    log = read_borealtc(Path(__file__).resolve().parents[1] / "fixtures" / "borealtc")[0]
    from energy import write_csv_log

    path = write_csv_log(log, tmp_path / "log.csv")
    assert len(read_csv_log(path)) == len(log)
    size = path.stat().st_size
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", str(4 * size))  # below 8x the file
    with pytest.raises(FileFormatError, match="more than the memory budget .* TERRAWATT_MEMORY_BUDGET_BYTES"):
        read_csv_log(path)
    pytest.importorskip("rosbags", reason="the bag reader needs the ros extra")
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "energy"))
    from robot_bags import write_robot_bag

    write_robot_bag(tmp_path / "h.bag", duration_s=4.0)  # 60 odometry, 120 imu, 40 status messages
    topics = BagTopics(cmd_vel_topic="/odometry/filtered", imu_topic="/imu/data", current_topics="/status",
                       current_fields=("left_driver_current", "right_driver_current"), voltage_field="battery_voltage",
                       drive_clock="currents")
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", str(100 * BAG_MESSAGE_BYTES))
    with pytest.raises(FileFormatError, match=r"the 2\d\d messages of topics .* more than the memory budget"):
        read_rosbag(tmp_path / "h.bag", topics)
    monkeypatch.delenv("TERRAWATT_MEMORY_BUDGET_BYTES")
    assert len(read_rosbag(tmp_path / "h.bag", topics)) > 0


@pytest.mark.parametrize("raw", ["0", "-5", "abc", "1e3", "1e30", "4.5"])
def test_a_budget_variable_that_is_not_a_byte_count_is_refused_not_replaced(monkeypatch, raw):
    from terrawatt_base.containers import memory_budget_bytes
    from terrawatt_base.errors import InvalidParameterError

    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", raw)
    with pytest.raises(InvalidParameterError, match="TERRAWATT_MEMORY_BUDGET_BYTES must be a positive whole number"):
        memory_budget_bytes()
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", "1_000_000")
    assert memory_budget_bytes() == 1_000_000
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", "")
    assert memory_budget_bytes() == 4 * 1024**3
