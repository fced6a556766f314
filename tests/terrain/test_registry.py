"""Tests of terrain.registry: per-cell model table, evidence, flags, updates, rollback, I/O."""

from __future__ import annotations

import json
import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest

from terrain import (
    CellModelRegistry,
    CurrentModelProtocol,
    DataError,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    TerrainMap,
    UnknownNameError,
    UpdatePolicy,
)


class GainModel:
    """Toy current model: current_a = gain_a * v_mps + offset_a."""

    def __init__(self, gain_a: float = 1.0, offset_a: float = 0.0) -> None:
        self.gain_a = gain_a
        self.offset_a = offset_a

    def fit(self, v_mps: np.ndarray, current_a: np.ndarray) -> GainModel:
        self.gain_a, self.offset_a = np.polyfit(v_mps, current_a, 1)
        return self

    def predict(self, v_mps: np.ndarray) -> np.ndarray:
        return self.gain_a * np.asarray(v_mps, float) + self.offset_a


def save_gain(model: GainModel, path: Path) -> None:
    with open(path, "wb") as fh:
        np.save(fh, np.array([model.gain_a, model.offset_a]))


def load_gain(path: Path) -> GainModel:
    with open(path, "rb") as fh:
        gain, offset = np.load(fh, allow_pickle=False)
    return GainModel(float(gain), float(offset))


def _registry(shape: tuple[int, int] = (4, 5)) -> CellModelRegistry:
    return CellModelRegistry(shape, GainModel(1.0), prior_name="physics", prior_meta={"kind": "physics"})


def _record_error(reg: CellModelRegistry, row: int, col: int, n: int, predicted_a: float,
                  measured_a: float = 1.0) -> None:
    """Record ``n`` one-second samples at one cell."""
    reg.record(np.full(n, row), np.full(n, col), np.full(n, measured_a), np.full(n, predicted_a), 1.0)


def _cell_predictions(reg: CellModelRegistry, v_mps: float = 0.7) -> np.ndarray:
    rows, cols = reg.shape
    return np.array([[float(reg.model_for(r, c).predict(v_mps)) for c in range(cols)] for r in range(rows)])


# ------------------------------------------------------------------------ policy
def test_policy_defaults_and_clear_level() -> None:
    p = UpdatePolicy(threshold_pct=12.0, min_samples=5, hysteresis_pct=4.5, min_region_cells=2)
    assert p.clear_below_pct == pytest.approx(7.5)
    assert isinstance(p.min_samples, int) and p.min_samples == 5


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"threshold_pct": 0.0}, "threshold_pct must be > 0"),
        ({"threshold_pct": -5.0}, "threshold_pct must be > 0"),
        ({"threshold_pct": float("nan")}, "threshold_pct must be finite"),
        ({"threshold_pct": "10"}, "threshold_pct must be a real number"),
        ({"min_samples": 0}, "min_samples must be >= 1"),
        ({"min_samples": 2.5}, "min_samples must be an integer"),
        ({"min_samples": True}, "min_samples must be an integer"),
        ({"hysteresis_pct": -1.0}, "hysteresis_pct must be >= 0"),
        ({"threshold_pct": 5.0, "hysteresis_pct": 5.0}, "hysteresis_pct must be >= 0 and < threshold_pct"),
        ({"hysteresis_pct": float("inf")}, "hysteresis_pct must be finite"),
        ({"min_region_cells": 0}, "min_region_cells must be >= 1"),
    ],
)
def test_policy_rejects_bad_values(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        UpdatePolicy(**kwargs)


# ------------------------------------------------------------------- model table
def test_protocol_and_model_table() -> None:
    reg = _registry()
    assert isinstance(GainModel(), CurrentModelProtocol)
    assert not isinstance(object(), CurrentModelProtocol)
    assert reg.prior_id == 0 and reg.model_ids == (0,)
    assert np.all(reg.model_id_map == 0) and reg.model_id_map.dtype == np.int32
    snow = GainModel(3.0)
    sid = reg.add_model(snow, name="snow", meta={"ground": "snow", "epochs": 40, "lr": 1e-3})
    assert sid == 1
    assert reg.model_id("snow") == 1 and reg.model(1) is snow
    assert dict(reg.model_record(1).meta) == {"ground": "snow", "epochs": 40, "lr": 1e-3}
    assert reg.model_record(0).name == "physics"
    # adding a model assigns no cell
    assert np.all(reg.model_id_map == 0)
    reg.assign((np.array([0, 3]), np.array([1, 4])), sid)
    mask = np.zeros((4, 5), bool)
    mask[2, :2] = True
    reg.assign(mask, sid)
    assert reg.model_for(0, 1) is snow and reg.model_for(3, 4) is snow and reg.model_for(2, 1) is snow
    assert reg.model_for(0, 0) is reg.model(0)
    assert int(np.count_nonzero(reg.model_id_map == sid)) == 4
    assert reg.model_ids_in_use().tolist() == [0, 1]


def test_model_id_map_is_read_only_copy() -> None:
    reg = _registry()
    view = reg.model_id_map
    with pytest.raises(ValueError):
        view[0, 0] = 5
    reg.assign(np.ones((4, 5), bool), reg.add_model(GainModel(2.0), name="m"))
    assert np.all(view == 0) and np.all(reg.model_id_map == 1)


def test_model_table_errors() -> None:
    reg = _registry()
    with pytest.raises(InvalidParameterError, match="fit\\(\\) and predict\\(\\)"):
        reg.add_model(object(), name="x")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="already in the registry"):
        reg.add_model(GainModel(), name="physics")
    with pytest.raises(InvalidParameterError, match="name must be a non-empty string"):
        reg.add_model(GainModel(), name="  ")
    with pytest.raises(InvalidParameterError, match=r"meta\['w'\] must be finite"):
        reg.add_model(GainModel(), name="a", meta={"w": float("nan")})
    with pytest.raises(InvalidParameterError, match=r"meta\['w'\] must be a str, int or float"):
        reg.add_model(GainModel(), name="a", meta={"w": [1, 2]})  # type: ignore[dict-item]
    with pytest.raises(UnknownNameError, match="no model with id 7"):
        reg.assign(np.ones((4, 5), bool), 7)
    with pytest.raises(UnknownNameError, match="no model named 'snow'"):
        reg.model_id("snow")
    with pytest.raises(OutOfBoundsError, match="outside the grid"):
        reg.model_for(4, 0)
    with pytest.raises(InvalidParameterError, match="selects no cell"):
        reg.assign(np.zeros((4, 5), bool), 0)
    with pytest.raises(InvalidParameterError, match="boolean mask"):
        reg.assign(np.ones((4, 5), int), 0)
    with pytest.raises(InvalidParameterError, match="shape must be"):
        CellModelRegistry((0, 3), GainModel())
    with pytest.raises(InvalidParameterError, match="given together"):
        CellModelRegistry((3, 3), GainModel(), cell_size_m=1.0)


# ------------------------------------------------------------------- grid binding
def test_grid_binding_and_mismatch() -> None:
    tmap = TerrainMap(np.zeros((4, 5)), cell_size_m=2.0, origin_xy_m=(10.0, 20.0))
    reg = CellModelRegistry.from_terrain(tmap, GainModel())
    assert reg.shape == (4, 5) and reg.cell_size_m == 2.0 and reg.origin_xy_m == (10.0, 20.0)
    reg.check_grid(tmap)  # same grid: no error
    with pytest.raises(GridMismatchError, match=r"shape \(5, 5\)"):
        reg.check_grid(TerrainMap(np.zeros((5, 5)), cell_size_m=2.0, origin_xy_m=(10.0, 20.0)))
    with pytest.raises(GridMismatchError, match="origin"):
        reg.check_grid(TerrainMap(np.zeros((4, 5)), cell_size_m=2.0, origin_xy_m=(0.0, 20.0)))
    with pytest.raises(GridMismatchError, match="mask has shape"):
        reg.assign(np.ones((5, 4), bool), 0)
    with pytest.raises(GridMismatchError, match="mask has shape"):
        reg.reset_evidence(np.ones((4, 4), bool))


# ----------------------------------------------------------------------- record
def test_record_sums_match_hand_computation() -> None:
    reg = _registry((3, 3))
    reg.record(
        rows=[0, 0, 1, 2],
        cols=[1, 1, 0, 2],
        measured_current_a=[1.0, 2.0, 3.0, 4.0],
        predicted_current_a=[2.0, 2.0, 2.0, 2.0],
        dt_s=[0.1, 0.2, 0.5, 1.0],
    )
    measured = np.zeros((3, 3))
    predicted = np.zeros((3, 3))
    measured[0, 1], predicted[0, 1] = 1.0 * 0.1 + 2.0 * 0.2, 2.0 * 0.1 + 2.0 * 0.2  # 0.5, 0.6
    measured[1, 0], predicted[1, 0] = 3.0 * 0.5, 2.0 * 0.5  # 1.5, 1.0
    measured[2, 2], predicted[2, 2] = 4.0, 2.0
    np.testing.assert_allclose(reg.measured_charge_c, measured)
    np.testing.assert_allclose(reg.predicted_charge_c, predicted)
    expected_count = np.zeros((3, 3), int)
    expected_count[0, 1], expected_count[1, 0], expected_count[2, 2] = 2, 1, 1
    np.testing.assert_array_equal(reg.sample_count, expected_count)
    err = reg.relative_error()
    assert err[0, 1] == pytest.approx(0.1 / 0.5)
    assert err[1, 0] == pytest.approx(-0.5 / 1.5)
    assert err[2, 2] == pytest.approx(-0.5)
    assert np.isnan(err[0, 0]) and np.count_nonzero(np.isnan(err)) == 6

    # 2-D currents (left, right) are summed per sample; a scalar dt applies to all samples
    reg.record([1], [0], [[1.0, 0.5]], [[2.0, 1.0]], 0.5)
    assert reg.measured_charge_c[1, 0] == pytest.approx(1.5 + 0.75)
    assert reg.predicted_charge_c[1, 0] == pytest.approx(1.0 + 1.5)
    assert reg.sample_count[1, 0] == 2


def test_record_matches_reference_loop_on_random_samples() -> None:
    rng = np.random.default_rng(7)
    reg = _registry((6, 7))
    n = 2000
    rows = rng.integers(0, 6, n)
    cols = rng.integers(0, 7, n)
    meas = rng.uniform(0.5, 4.0, (n, 2))
    pred = rng.uniform(0.5, 4.0, (n, 2))
    dt = rng.uniform(0.005, 0.02, n)
    reg.record(rows[:1200], cols[:1200], meas[:1200], pred[:1200], dt[:1200])
    reg.record(rows[1200:], cols[1200:], meas[1200:], pred[1200:], dt[1200:])
    ref_m = np.zeros((6, 7))
    ref_p = np.zeros((6, 7))
    ref_n = np.zeros((6, 7), int)
    for i in range(n):  # reference, deliberately a plain loop
        ref_m[rows[i], cols[i]] += meas[i].sum() * dt[i]
        ref_p[rows[i], cols[i]] += pred[i].sum() * dt[i]
        ref_n[rows[i], cols[i]] += 1
    np.testing.assert_allclose(reg.measured_charge_c, ref_m, rtol=1e-12)
    np.testing.assert_allclose(reg.predicted_charge_c, ref_p, rtol=1e-12)
    np.testing.assert_array_equal(reg.sample_count, ref_n)


def test_relative_error_with_zero_measured_charge() -> None:
    reg = _registry((2, 2))
    reg.record([0, 1], [0, 1], [0.0, 0.0], [0.0, 1.0], 1.0)
    err = reg.relative_error()
    assert err[0, 0] == 0.0 and err[1, 1] == np.inf and np.isnan(err[0, 1])


@pytest.mark.parametrize(
    ("args", "exc", "match"),
    [
        (([0, 1], [0], [1.0, 1.0], [1.0, 1.0], 0.1), InvalidParameterError, "same length"),
        (([0, 1], [0, 1], [1.0], [1.0, 1.0], 0.1), InvalidParameterError, "measured_current_a must have shape"),
        (([0, 1], [0, 1], [1.0, 1.0], [1.0, 1.0, 1.0], 0.1), InvalidParameterError,
         "predicted_current_a must have shape"),
        (([0, 1], [0, 1], [1.0, 1.0], [1.0, 1.0], [0.1, 0.1, 0.1]), InvalidParameterError, "dt_s must be"),
        (([0, 1], [0, 1], [1.0, np.nan], [1.0, 1.0], 0.1), DataError, "measured_current_a holds NaN"),
        (([0, 1], [0, 1], [1.0, 1.0], [np.inf, 1.0], 0.1), DataError, "predicted_current_a holds NaN/inf"),
        (([0, 1], [0, 1], [1.0, 1.0], [1.0, 1.0], [0.1, np.nan]), DataError, "dt_s must be finite and > 0"),
        (([0, 1], [0, 1], [1.0, 1.0], [1.0, 1.0], 0.0), DataError, "dt_s must be finite and > 0"),
        (([0, 9], [0, 1], [1.0, 1.0], [1.0, 1.0], 0.1), OutOfBoundsError, "row=9"),
        (([0.0, 1.0], [0, 1], [1.0, 1.0], [1.0, 1.0], 0.1), InvalidParameterError, "integer cell indices"),
    ],
)
def test_record_rejects_bad_input_and_records_nothing(args: tuple, exc: type, match: str) -> None:
    reg = _registry()
    with pytest.raises(exc, match=match):
        reg.record(*args)
    assert reg.sample_count.sum() == 0 and reg.measured_charge_c.sum() == 0.0


# ------------------------------------------------------------------------ flags
def test_threshold_min_samples_and_hysteresis() -> None:
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=4, hysteresis_pct=4.0)  # clears below 6 %
    reg = _registry((3, 3))
    _record_error(reg, 0, 0, 4, predicted_a=1.05)  # 5 % with enough samples: below threshold
    _record_error(reg, 0, 1, 4, predicted_a=1.25)  # +25 %: above
    _record_error(reg, 0, 2, 4, predicted_a=0.75)  # -25 %: above (magnitude counts)
    _record_error(reg, 1, 0, 3, predicted_a=1.25)  # +25 % but only 3 samples
    flags = reg.flagged(policy)
    expected = np.zeros((3, 3), bool)
    expected[0, 1] = expected[0, 2] = True
    np.testing.assert_array_equal(flags, expected)

    _record_error(reg, 1, 0, 1, predicted_a=1.25)  # now 4 samples
    assert reg.flagged(policy)[1, 0]

    # cell (0, 1): P = 5, M = 4; 8 exact samples -> 1/12 = 8.3 %: between 6 % and 10 %, stays flagged
    _record_error(reg, 0, 1, 8, predicted_a=1.0)
    assert reg.relative_error()[0, 1] == pytest.approx(1 / 12)
    assert reg.flagged(policy)[0, 1]
    # a never-flagged cell at the same 8.3 % is not flagged (hysteresis only keeps a flag)
    _record_error(reg, 2, 2, 11, predicted_a=1.0)
    _record_error(reg, 2, 2, 1, predicted_a=2.0)  # P = 13, M = 12 -> 8.3 %
    assert reg.relative_error()[2, 2] == pytest.approx(1 / 12)
    assert not reg.flagged(policy)[2, 2]
    # six more exact samples -> 1/18 = 5.6 % < 6 %: cleared
    _record_error(reg, 0, 1, 6, predicted_a=1.0)
    flags = reg.flagged(policy)
    assert not flags[0, 1] and flags[0, 2] and flags[1, 0]
    np.testing.assert_array_equal(reg.flag_state, flags)


def test_reset_evidence_clears_counts_and_flags_only_in_cells() -> None:
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=2.0)
    reg = _registry((3, 3))
    reg.record([0, 2], [0, 2], [1.0, 1.0], [2.0, 2.0], 1.0)
    assert reg.flagged(policy).sum() == 2
    mask = np.zeros((3, 3), bool)
    mask[0, 0] = True
    reg.reset_evidence(mask)
    assert reg.sample_count[0, 0] == 0 and np.isnan(reg.relative_error()[0, 0])
    assert reg.sample_count[2, 2] == 1
    assert reg.flag_state.tolist() == [[False] * 3, [False] * 3, [False, False, True]]
    reg.reset_evidence()
    assert reg.sample_count.sum() == 0 and not reg.flag_state.any()


def test_flagged_regions_components_bbox_and_world_points() -> None:
    tmap = TerrainMap(np.zeros((6, 6)), cell_size_m=2.0, origin_xy_m=(10.0, 20.0))
    reg = CellModelRegistry.from_terrain(tmap, GainModel())
    # L-shaped region A: (0,0), (1,0), (2,0), (2,1), (2,2); its centroid (1.4, 0.6) is nearest (1, 0)
    a_rows, a_cols = np.array([0, 1, 2, 2, 2]), np.array([0, 0, 2, 1, 0])
    # region B touches (4,4) and (5,5) only diagonally; single cell C at (0,5)
    b_rows, b_cols = np.array([4, 5]), np.array([4, 5])
    rows = np.concatenate([a_rows, b_rows, [0]])
    cols = np.concatenate([a_cols, b_cols, [5]])
    n = rows.size
    reg.assign((np.array([2]), np.array([2])), reg.add_model(GainModel(2.0), name="sand"))
    reg.record(rows, cols, np.full(n, 2.0), np.full(n, 3.0), 0.5)  # +50 % everywhere
    reg.record([0, 0], [0, 5], [1.0, 1.0], [1.0, 1.0], 1.0)  # dilute two cells (still > 10 %)
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=1.0)

    regions = reg.flagged_regions(policy, connectivity=8)
    assert [r.cell_count for r in regions] == [5, 1, 2]
    a, c, b = regions
    assert a.bbox_rows_cols == (0, 0, 2, 2)
    assert a.representative_row_col == (1, 0)
    assert a.representative_xy_m == (11.0, 23.0)
    assert a.bounds_m == (10.0, 20.0, 16.0, 26.0)
    assert sorted(zip(a.rows.tolist(), a.cols.tolist())) == sorted(zip(a_rows.tolist(), a_cols.tolist()))
    # region error integrates charge: P = 5*1.5 + 1, M = 5*1.0 + 1
    assert a.relative_error == pytest.approx((8.5 - 6.0) / 6.0)
    assert a.sample_count == 6 and a.model_ids == (0, 1) and b.model_ids == (0,)
    assert c.representative_row_col == (0, 5) and b.bbox_rows_cols == (4, 4, 5, 5)
    np.testing.assert_array_equal(a.mask(reg.shape)[a_rows, a_cols], True)
    assert a.mask(reg.shape).sum() == 5

    four = reg.flagged_regions(policy, connectivity=4)
    assert sorted(r.cell_count for r in four) == [1, 1, 1, 5]
    big_only = reg.flagged_regions(UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=1.0,
                                                min_region_cells=2))
    assert [r.cell_count for r in big_only] == [5, 2]
    # regions without georeferencing carry no world coordinates
    plain = _registry((2, 2))
    plain.record([0], [0], [1.0], [2.0], 1.0)
    (only,) = plain.flagged_regions(policy)
    assert only.representative_xy_m is None and only.bounds_m is None
    with pytest.raises(InvalidParameterError, match="connectivity must be 4 or 8"):
        reg.flagged_regions(policy, connectivity=6)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="policy must be an UpdatePolicy"):
        reg.flagged({"threshold_pct": 10})  # type: ignore[arg-type]


# -------------------------------------------------------------------- updates
def test_worse_model_is_rejected_and_old_one_kept() -> None:
    reg = _registry()
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=2.0)
    reg.record([1, 1], [1, 2], [1.0, 1.0], [2.0, 2.0], 1.0)
    (region,) = reg.flagged_regions(policy)
    before = reg.model_id_map
    for err_new in (0.30, 0.20):  # worse, then equal: both rejected
        decision = reg.propose_update(region, GainModel(9.0), err_new, 0.20, name="snow-v1", reason="test")
        assert not decision.accepted and decision.model_id is None and decision.version is None
        assert decision.improvement == pytest.approx(0.20 - err_new) and decision.cell_count == 2
    np.testing.assert_array_equal(reg.model_id_map, before)
    assert reg.history == [] and reg.model_ids == (0,)
    assert reg.sample_count.sum() == 2 and reg.flag_state.sum() == 2  # evidence untouched
    assert reg.model_for(1, 1) is reg.model(0)

    better = GainModel(1.5)
    decision = reg.propose_update(region, better, 0.05, 0.20, name="snow-v1", reason="error 100 %",
                                  meta={"ground": "snow"})
    assert decision.accepted and decision.model_id == 1 and decision.version == 1
    assert decision.improvement == pytest.approx(0.15)
    assert reg.model_for(1, 1) is better and reg.model_for(1, 2) is better
    assert int(np.count_nonzero(reg.model_id_map == 1)) == 2
    assert reg.sample_count.sum() == 0 and not reg.flag_state.any()  # evidence reset in the region
    (v,) = reg.history
    assert (v.version, v.kind, v.model_id, v.cell_count, v.reason) == (1, "update", 1, 2, "error 100 %")
    assert (v.validation_error_new, v.validation_error_old) == (0.05, 0.20)
    assert v.previous_model_ids.tolist() == [0, 0]


@pytest.mark.parametrize(
    ("errors", "match"),
    [((float("nan"), 0.1), "validation_error_new must be finite"),
     ((0.1, -0.2), "validation_error_old must be >= 0"),
     ((0.1, float("inf")), "validation_error_old must be finite")],
)
def test_propose_update_rejects_bad_errors(errors: tuple[float, float], match: str) -> None:
    reg = _registry()
    with pytest.raises(InvalidParameterError, match=match):
        reg.propose_update(np.ones((4, 5), bool), GainModel(), *errors, name="m", reason="r")
    assert reg.model_ids == (0,)


def test_propose_update_rejects_empty_region_and_duplicate_name() -> None:
    reg = _registry()
    with pytest.raises(InvalidParameterError, match="region selects no cell"):
        reg.propose_update(np.zeros((4, 5), bool), GainModel(), 0.1, 0.2, name="m", reason="r")
    with pytest.raises(InvalidParameterError, match="already in the registry"):
        reg.propose_update(np.ones((4, 5), bool), GainModel(), 0.1, 0.2, name="physics", reason="r")


def test_rollback_restores_exact_assignment_and_predictions() -> None:
    reg = _registry((4, 5))
    initial_pred = _cell_predictions(reg)
    m1 = reg.add_model(GainModel(2.0, 0.1), name="sand")
    left = np.zeros((4, 5), bool)
    left[:, :3] = True
    v1 = reg.assign(left, m1, reason="known sand")
    after_v1_map = reg.model_id_map
    after_v1_pred = _cell_predictions(reg)
    top = np.zeros((4, 5), bool)
    top[2:, 1:] = True  # overlaps sand cells and prior cells
    d = reg.propose_update(top, GainModel(3.0, -0.2), 0.04, 0.3, name="snow", reason="flagged")
    assert d.accepted and reg.version == 2
    assert not np.array_equal(_cell_predictions(reg), after_v1_pred)

    undone = reg.rollback()
    assert [u.version for u in undone] == [2]
    np.testing.assert_array_equal(reg.model_id_map, after_v1_map)
    np.testing.assert_array_equal(_cell_predictions(reg), after_v1_pred)
    assert reg.version == v1.version == 1

    # a new change after a rollback gets a fresh version number
    v3 = reg.assign((np.array([0]), np.array([4])), reg.model_id("snow"))
    assert v3.version == 3 and [v.version for v in reg.history] == [1, 3]
    undone = reg.rollback(version=0)
    assert [u.version for u in undone] == [3, 1]
    assert np.all(reg.model_id_map == 0) and reg.history == []
    np.testing.assert_array_equal(_cell_predictions(reg), initial_pred)
    assert reg.model_ids == (0, 1, 2)  # models stay in the table

    with pytest.raises(InvalidParameterError, match="nothing to roll back"):
        reg.rollback()
    reg.assign(left, m1)
    with pytest.raises(InvalidParameterError, match="version must be 0 or one of"):
        reg.rollback(version=2)


def test_rollback_to_a_middle_version_and_evidence_reset() -> None:
    reg = _registry((3, 3))
    ids = [reg.add_model(GainModel(float(k)), name=f"m{k}") for k in (2, 3, 4)]
    maps = [reg.model_id_map]
    for k, mid in enumerate(ids):
        mask = np.zeros((3, 3), bool)
        mask[: k + 1, : k + 1] = True
        reg.assign(mask, mid)
        maps.append(reg.model_id_map)
    reg.record([0, 2, 1], [0, 2, 2], [1.0, 1.0, 1.0], [1.5, 1.5, 1.5], 1.0)
    reg.rollback(version=2)
    np.testing.assert_array_equal(reg.model_id_map, maps[2])
    # (2, 2) and (1, 2) changed model (m4 -> prior / m3): evidence reset; (0, 0) changed m4 -> m3
    assert reg.sample_count.sum() == 0
    reg.record([0, 1], [0, 0], [1.0, 1.0], [1.5, 1.5], 1.0)
    reg.rollback(version=1)
    np.testing.assert_array_equal(reg.model_id_map, maps[1])
    assert reg.sample_count[0, 0] == 0 and reg.sample_count[1, 0] == 0  # both changed m3 -> m2 / prior
    reg.record([0], [0], [1.0], [1.5], 1.0)
    reg.assign((np.array([0]), np.array([0])), ids[0])  # same model as before: evidence kept
    assert reg.sample_count[0, 0] == 1


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
    reg.record(rows, cols, rng.uniform(1, 2, 300), rng.uniform(1, 3, 300), 0.01)
    policy = UpdatePolicy(threshold_pct=20.0, min_samples=3, hysteresis_pct=5.0)
    regions = reg.flagged_regions(policy)
    reg.propose_update(regions[0], GainModel(2.5, -0.1), 0.03, 0.4, name="snow", reason="region 1 > 20 %")
    reg.record(rows[:50], cols[:50], np.ones(50), np.full(50, 1.5), 0.01)
    reg.flagged(policy)
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
    np.testing.assert_array_equal(back.measured_charge_c, reg.measured_charge_c)
    np.testing.assert_array_equal(back.predicted_charge_c, reg.predicted_charge_c)
    np.testing.assert_array_equal(back.sample_count, reg.sample_count)
    np.testing.assert_array_equal(back.flag_state, reg.flag_state)
    np.testing.assert_array_equal(_cell_predictions(back), _cell_predictions(reg))
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
    np.testing.assert_array_equal(back.flagged(policy), reg.flagged(policy))
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
    reg = _registry()
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
