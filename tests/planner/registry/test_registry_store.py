"""Tests of planner.registry.store: save, load, recovery of interrupted saves, corrupt directories."""

from __future__ import annotations

import json
import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest
from registry_models import GainModel, cell_predictions, load_gain, registry, save_gain

from planner.registry import CellModelRegistry, UpdatePolicy
from terrain import FileFormatError, FormatVersionError, GridMismatchError, InvalidParameterError, TerrainMap


# ------------------------------------------------------------------- persistence
def _populated(tmp_path: Path) -> tuple[CellModelRegistry, TerrainMap]:
    tmap = TerrainMap(np.zeros((5, 6)), cell_size_m=0.5, origin_xy_m=(-1.0, 2.0))
    reg = CellModelRegistry.from_terrain(tmap, GainModel(1.0, 0.2), prior_name="physics",
                                         prior_meta={"kind": "physics", "version": 2})
    sand = reg.add_model(GainModel(2.0), name="sand", meta={"ground": "sand"})
    mask = np.zeros((5, 6), bool)
    mask[:, :2] = True
    reg.assign(mask, sand, reason="ground layer")
    rng = np.random.default_rng(3)
    rows, cols = rng.integers(0, 5, 300), rng.integers(0, 6, 300)
    reg.evidence.record(rows, cols, rng.uniform(1, 2, 300), rng.uniform(1, 3, 300), 0.01)
    policy = UpdatePolicy(threshold_pct=20.0, min_samples=3, hysteresis_pct=5.0)
    regions = reg.evidence.flagged_regions(policy)
    reg.propose_update(regions[0], GainModel(2.5, -0.1), 0.03, 0.4, name="snow", reason="region 1 > 20 %")
    reg.evidence.record(rows[:50], cols[:50], np.ones(50), np.full(50, 1.5), 0.01)
    reg.evidence.flagged(policy)
    return reg, tmap


def test_save_load_round_trip(tmp_path: Path) -> None:
    reg, tmap = _populated(tmp_path)
    out = reg.save(tmp_path / "reg", save_gain, model_suffix=".npy")
    assert sorted(p.name for p in out.iterdir()) == ["history.json", "models", "registry.npz"]
    assert stat.S_IMODE(out.stat().st_mode) == 0o755  # not mkdtemp's owner-only 0700
    assert sorted(p.name for p in (out / "models").iterdir()) == [
        "model-0000.npy", "model-0001.npy", "model-0002.npy"]
    back = CellModelRegistry.load(out, load_gain, terrain=tmap)
    assert back.shape == reg.shape and back.cell_size_m == 0.5 and back.origin_xy_m == (-1.0, 2.0)
    np.testing.assert_array_equal(back.model_id_map, reg.model_id_map)
    np.testing.assert_array_equal(back.evidence.measured_charge_c, reg.evidence.measured_charge_c)
    np.testing.assert_array_equal(back.evidence.predicted_charge_c, reg.evidence.predicted_charge_c)
    np.testing.assert_array_equal(back.evidence.sample_count, reg.evidence.sample_count)
    np.testing.assert_array_equal(back.evidence.flag_state, reg.evidence.flag_state)
    np.testing.assert_array_equal(cell_predictions(back), cell_predictions(reg))
    assert [back.model_record(i).name for i in back.model_ids] == ["physics", "sand", "snow"]
    assert dict(back.model_record(0).meta) == {"kind": "physics", "version": 2}
    assert len(back.history) == len(reg.history) == 2
    for a, b in zip(back.history, reg.history):
        assert (a.version, a.kind, a.model_id, a.cell_count, a.reason) == (
            b.version, b.kind, b.model_id, b.cell_count, b.reason)
        assert a.validation_error_new == b.validation_error_new
        assert a.validation_error_old == b.validation_error_old
        np.testing.assert_array_equal(a.rows, b.rows)
        np.testing.assert_array_equal(a.cols, b.cols)
        np.testing.assert_array_equal(a.previous_model_ids, b.previous_model_ids)
    # the loaded registry rolls back exactly like the original
    before_update = reg.model_id_map.copy()
    reg.rollback()
    back.rollback()
    np.testing.assert_array_equal(back.model_id_map, reg.model_id_map)
    assert not np.array_equal(back.model_id_map, before_update)
    # hysteresis state survives: same flags on the next call
    policy = UpdatePolicy(threshold_pct=20.0, min_samples=3, hysteresis_pct=5.0)
    np.testing.assert_array_equal(back.evidence.flagged(policy), reg.evidence.flagged(policy))
    # the loaded evidence knows the grid (world coordinates) and the current cell map (each region's models)
    loose = UpdatePolicy(threshold_pct=1.0, min_samples=1, hysteresis_pct=0.5)
    regions, back_regions = reg.evidence.flagged_regions(loose), back.evidence.flagged_regions(loose)
    assert regions and [(r.bounds_m, r.model_ids) for r in back_regions] == [(r.bounds_m, r.model_ids) for r in regions]
    assert all(r.bounds_m is not None for r in back_regions)
    with pytest.raises(GridMismatchError, match="shape"):
        CellModelRegistry.load(out, load_gain, terrain=TerrainMap(np.zeros((6, 5)), cell_size_m=0.5))


def test_save_replaces_previous_registry_and_keeps_it_on_failure(tmp_path: Path) -> None:
    reg, _ = _populated(tmp_path)
    target = tmp_path / "reg"
    reg.save(target, save_gain)
    reg.rollback(version=0)
    reg.save(target, save_gain)  # replaces the previous registry
    assert np.all(CellModelRegistry.load(target, load_gain).model_id_map == 0)

    reg.assign(np.ones(reg.shape, bool), reg.model_id("snow"))

    def failing(model: GainModel, path: Path) -> None:
        if model.gain_a == 2.5:
            raise RuntimeError("disk full")
        save_gain(model, path)

    with pytest.raises(RuntimeError, match="disk full"):
        reg.save(target, failing)
    # the previous directory is intact and no temporary directory is left behind
    assert np.all(CellModelRegistry.load(target, load_gain).model_id_map == 0)
    assert sorted(os.listdir(tmp_path)) == ["reg"]

    with pytest.raises(InvalidParameterError, match="wrote nothing"):
        reg.save(target, lambda model, path: None)
    assert sorted(os.listdir(tmp_path)) == ["reg"]


def test_load_recovers_the_registry_a_crashed_save_left_aside(tmp_path: Path) -> None:
    # a save killed between its two renames: the previous registry sits in save's hidden
    # holder (.reg.*.old/reg) and nothing is under the name; load moves it back
    import tempfile

    from terrain import RecoveryWarning

    reg, _ = _populated(tmp_path)
    target = reg.save(tmp_path / "reg", save_gain)
    holder = Path(tempfile.mkdtemp(prefix=".reg.", suffix=".old", dir=tmp_path))
    os.rename(target, holder / "reg")
    with pytest.warns(RecoveryWarning, match="interrupted save"):
        back = CellModelRegistry.load(target, load_gain)
    np.testing.assert_array_equal(back.model_id_map, reg.model_id_map)
    assert sorted(os.listdir(tmp_path)) == ["reg"]  # the holder is gone
    shutil.rmtree(target)
    with pytest.raises(FileFormatError, match="does not exist"):  # nothing to recover
        CellModelRegistry.load(target, load_gain)


def test_save_refuses_to_replace_a_foreign_directory(tmp_path: Path) -> None:
    reg = registry()
    foreign = tmp_path / "docs"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep me")
    with pytest.raises(InvalidParameterError, match="not a registry directory"):
        reg.save(foreign, save_gain)
    assert (foreign / "notes.txt").read_text() == "keep me"
    with pytest.raises(InvalidParameterError, match="model_suffix"):
        reg.save(tmp_path / "r", save_gain, model_suffix="/x")


def test_load_corrupt_or_missing_pieces(tmp_path: Path) -> None:
    reg, _ = _populated(tmp_path)
    good = reg.save(tmp_path / "good", save_gain)

    def fresh(name: str) -> Path:
        return reg.save(tmp_path / name, save_gain)

    with pytest.raises(FileFormatError, match="does not exist"):
        CellModelRegistry.load(tmp_path / "nowhere", load_gain)

    d = fresh("corrupt_npz")
    (d / "registry.npz").write_bytes(b"PK\x03\x04 this is not a zip archive")
    with pytest.raises(FileFormatError, match="registry.npz.*corrupt"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("missing_npz")
    (d / "registry.npz").unlink()
    with pytest.raises(FileFormatError, match="registry.npz.*missing"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("foreign_npz")
    with open(d / "registry.npz", "wb") as fh:
        np.savez(fh, something=np.zeros(3))
    with pytest.raises(FileFormatError, match="not a terrawatt cell-model registry"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("bad_history")
    (d / "history.json").write_text("{ truncated")
    with pytest.raises(FileFormatError, match="history.json.*corrupt"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("foreign_history")
    (d / "history.json").write_text(json.dumps({"format": "terrawatt-batch", "format_version": 1}))
    with pytest.raises(FileFormatError, match="history.json' is not a terrawatt registry history"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("missing_history")
    (d / "history.json").unlink()
    with pytest.raises(FileFormatError, match="history.json.*missing"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("missing_model")
    (d / "models" / "model-0001").unlink()
    with pytest.raises(FileFormatError, match="model-0001.*missing"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("corrupt_model")
    (d / "models" / "model-0002").write_bytes(b"garbage")
    with pytest.raises(FileFormatError, match="model-0002.*could not be loaded"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("bad_map")
    with np.load(d / "registry.npz") as data:
        content = {k: data[k] for k in data.files}
    content["model_id_map"] = np.full(content["model_id_map"].shape, 7, np.int32)
    with open(d / "registry.npz", "wb") as fh:
        np.savez(fh, **content)
    with pytest.raises(FileFormatError, match="outside the model table"):
        CellModelRegistry.load(d, load_gain)

    d = fresh("escaping_file")
    hist = json.loads((d / "history.json").read_text())
    hist["models"][1]["file"] = "../good/models/model-0001"
    (d / "history.json").write_text(json.dumps(hist))
    with pytest.raises(FileFormatError, match="no valid 'file'"):
        CellModelRegistry.load(d, load_gain)

    assert CellModelRegistry.load(good, load_gain).model_ids == (0, 1, 2)


def test_load_other_format_version(tmp_path: Path) -> None:
    reg, _ = _populated(tmp_path)
    d = reg.save(tmp_path / "npz_version", save_gain)
    with np.load(d / "registry.npz") as data:
        content = {k: data[k] for k in data.files}
    content["__version__"] = np.array(99)
    with open(d / "registry.npz", "wb") as fh:
        np.savez(fh, **content)
    with pytest.raises(FormatVersionError, match="format version 99"):
        CellModelRegistry.load(d, load_gain)

    d = reg.save(tmp_path / "json_version", save_gain)
    hist = json.loads((d / "history.json").read_text())
    hist["format_version"] = 99
    (d / "history.json").write_text(json.dumps(hist))
    with pytest.raises(FormatVersionError, match="history.json.*format version 99"):
        CellModelRegistry.load(d, load_gain)


# ----------------------------------------------------------- killed saves
def _leftover(tmp_path: Path, name: str, pid: int, tag: str) -> Path:
    """A temporary folder as a save of ``name`` by ``pid`` leaves it when killed mid-write."""
    folder = tmp_path / f".{name}.{pid}.{tag}.tmp"
    (folder / "models").mkdir(parents=True)
    (folder / "registry.npz").write_bytes(b"half written")
    return folder


def test_save_and_load_remove_temporaries_of_dead_saves_only(tmp_path: Path, dead_pid: int, live_pid: int) -> None:
    reg = registry()
    target = reg.save(tmp_path / "reg", save_gain)
    dead = _leftover(tmp_path, "reg", dead_pid, "k1ll3d_0")
    live = _leftover(tmp_path, "reg", live_pid, "running")
    other = _leftover(tmp_path, "reg2", dead_pid, "k1ll3d_0")  # another target's
    reg.save(target, save_gain)
    assert not dead.exists() and live.exists() and other.exists()
    dead = _leftover(tmp_path, "reg", dead_pid, "k1ll3d_1")
    assert CellModelRegistry.load(target, load_gain).shape == reg.shape
    assert not dead.exists() and live.exists() and other.exists()
    assert sorted(os.listdir(tmp_path)) == sorted(["reg", live.name, other.name])


def test_the_registry_a_killed_save_moved_aside_comes_back(tmp_path: Path, dead_pid: int) -> None:
    from terrain import RecoveryWarning

    reg, _ = _populated(tmp_path)
    target = reg.save(tmp_path / "reg", save_gain)
    # killed between its renames: the old registry moved aside, the new one complete but not renamed
    aside = tmp_path / f".reg.{dead_pid}.aside000.tmp"
    aside.mkdir()
    os.rename(target, aside / "old")
    half_new = _leftover(tmp_path, "reg", dead_pid, "new00000")
    with pytest.warns(RecoveryWarning, match="interrupted save"):
        back = CellModelRegistry.load(target, load_gain)
    np.testing.assert_array_equal(back.model_id_map, reg.model_id_map)
    assert sorted(os.listdir(tmp_path)) == ["reg"] and not half_new.exists()
    # the same on the next save: the previous registry is back before the new one is written
    os.rename(target, tmp_path / "moved")
    aside.mkdir()
    os.rename(tmp_path / "moved", aside / "old")

    def failing(model: GainModel, path: Path) -> None:
        raise RuntimeError("disk full")

    with pytest.warns(RecoveryWarning), pytest.raises(RuntimeError, match="disk full"):
        reg.save(target, failing)
    assert sorted(os.listdir(tmp_path)) == ["reg"]
    np.testing.assert_array_equal(CellModelRegistry.load(target, load_gain).model_id_map, reg.model_id_map)


def test_save_onto_a_file_and_a_malformed_history(tmp_path: Path) -> None:
    reg, _ = _populated(tmp_path)
    (tmp_path / "file").write_text("not a folder")
    with pytest.raises(InvalidParameterError, match="not a registry directory"):
        reg.save(tmp_path / "file", save_gain)
    d = reg.save(tmp_path / "lists", save_gain)
    hist = json.loads((d / "history.json").read_text())
    hist["versions"] = 7
    (d / "history.json").write_text(json.dumps(hist))
    with pytest.raises(FileFormatError, match="history.json.*malformed"):
        CellModelRegistry.load(d, load_gain)
    d = reg.save(tmp_path / "nested", save_gain)
    (d / "history.json").write_text("[" * 100_000)
    with pytest.raises(FileFormatError, match="history.json.*corrupt"):
        CellModelRegistry.load(d, load_gain)
