"""Tests of planner.registry.evidence (through the registry): policy, recorded charge, errors, flags, regions."""

from __future__ import annotations

import numpy as np
import pytest
from registry_models import GainModel, record_error, registry

from planner.registry import CellModelRegistry, UpdatePolicy
from planner.registry.evidence import relative_error
from terrain import DataError, InvalidParameterError, OutOfBoundsError, TerrainMap


# ----------------------------------------------------------------------- record
def test_record_sums_match_hand_computation() -> None:
    reg = registry((3, 3))
    reg.evidence.record(
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
    np.testing.assert_allclose(reg.evidence.measured_charge_c, measured)
    np.testing.assert_allclose(reg.evidence.predicted_charge_c, predicted)
    expected_count = np.zeros((3, 3), int)
    expected_count[0, 1], expected_count[1, 0], expected_count[2, 2] = 2, 1, 1
    np.testing.assert_array_equal(reg.evidence.sample_count, expected_count)
    err = reg.evidence.relative_error()
    assert err[0, 1] == pytest.approx(0.1 / 0.5)
    assert err[1, 0] == pytest.approx(-0.5 / 1.5)
    assert err[2, 2] == pytest.approx(-0.5)
    assert np.isnan(err[0, 0]) and np.count_nonzero(np.isnan(err)) == 6

    # 2-D currents (left, right) are summed per sample; a scalar dt applies to all samples
    reg.evidence.record([1], [0], [[1.0, 0.5]], [[2.0, 1.0]], 0.5)
    assert reg.evidence.measured_charge_c[1, 0] == pytest.approx(1.5 + 0.75)
    assert reg.evidence.predicted_charge_c[1, 0] == pytest.approx(1.0 + 1.5)
    assert reg.evidence.sample_count[1, 0] == 2


def test_record_matches_reference_loop_on_random_samples() -> None:
    rng = np.random.default_rng(7)
    reg = registry((6, 7))
    n = 2000
    rows = rng.integers(0, 6, n)
    cols = rng.integers(0, 7, n)
    meas = rng.uniform(0.5, 4.0, (n, 2))
    pred = rng.uniform(0.5, 4.0, (n, 2))
    dt = rng.uniform(0.005, 0.02, n)
    reg.evidence.record(rows[:1200], cols[:1200], meas[:1200], pred[:1200], dt[:1200])
    reg.evidence.record(rows[1200:], cols[1200:], meas[1200:], pred[1200:], dt[1200:])
    ref_m = np.zeros((6, 7))
    ref_p = np.zeros((6, 7))
    ref_n = np.zeros((6, 7), int)
    for i in range(n):  # reference, deliberately a plain loop
        ref_m[rows[i], cols[i]] += meas[i].sum() * dt[i]
        ref_p[rows[i], cols[i]] += pred[i].sum() * dt[i]
        ref_n[rows[i], cols[i]] += 1
    np.testing.assert_allclose(reg.evidence.measured_charge_c, ref_m, rtol=1e-12)
    np.testing.assert_allclose(reg.evidence.predicted_charge_c, ref_p, rtol=1e-12)
    np.testing.assert_array_equal(reg.evidence.sample_count, ref_n)


def test_relative_error_with_zero_measured_charge() -> None:
    reg = registry((2, 2))
    reg.evidence.record([0, 1], [0, 1], [0.0, 0.0], [0.0, 1.0], 1.0)
    err = reg.evidence.relative_error()
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
    reg = registry()
    with pytest.raises(exc, match=match):
        reg.evidence.record(*args)
    assert reg.evidence.sample_count.sum() == 0 and reg.evidence.measured_charge_c.sum() == 0.0


# ------------------------------------------------------------------------ flags
def test_threshold_min_samples_and_hysteresis() -> None:
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=4, hysteresis_pct=4.0)  # clears below 6 %
    reg = registry((3, 3))
    record_error(reg, 0, 0, 4, predicted_a=1.05)  # 5 % with enough samples: below threshold
    record_error(reg, 0, 1, 4, predicted_a=1.25)  # +25 %: above
    record_error(reg, 0, 2, 4, predicted_a=0.75)  # -25 %: above (magnitude counts)
    record_error(reg, 1, 0, 3, predicted_a=1.25)  # +25 % but only 3 samples
    flags = reg.evidence.flagged(policy)
    expected = np.zeros((3, 3), bool)
    expected[0, 1] = expected[0, 2] = True
    np.testing.assert_array_equal(flags, expected)

    record_error(reg, 1, 0, 1, predicted_a=1.25)  # now 4 samples
    assert reg.evidence.flagged(policy)[1, 0]

    # cell (0, 1): P = 5, M = 4; 8 exact samples -> 1/12 = 8.3 %: between 6 % and 10 %, stays flagged
    record_error(reg, 0, 1, 8, predicted_a=1.0)
    assert reg.evidence.relative_error()[0, 1] == pytest.approx(1 / 12)
    assert reg.evidence.flagged(policy)[0, 1]
    # a never-flagged cell at the same 8.3 % is not flagged (hysteresis only keeps a flag)
    record_error(reg, 2, 2, 11, predicted_a=1.0)
    record_error(reg, 2, 2, 1, predicted_a=2.0)  # P = 13, M = 12 -> 8.3 %
    assert reg.evidence.relative_error()[2, 2] == pytest.approx(1 / 12)
    assert not reg.evidence.flagged(policy)[2, 2]
    # six more exact samples -> 1/18 = 5.6 % < 6 %: cleared
    record_error(reg, 0, 1, 6, predicted_a=1.0)
    flags = reg.evidence.flagged(policy)
    assert not flags[0, 1] and flags[0, 2] and flags[1, 0]
    np.testing.assert_array_equal(reg.evidence.flag_state, flags)


def test_reset_evidence_clears_counts_and_flags_only_in_cells() -> None:
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=2.0)
    reg = registry((3, 3))
    reg.evidence.record([0, 2], [0, 2], [1.0, 1.0], [2.0, 2.0], 1.0)
    assert reg.evidence.flagged(policy).sum() == 2
    mask = np.zeros((3, 3), bool)
    mask[0, 0] = True
    reg.evidence.reset(mask)
    assert reg.evidence.sample_count[0, 0] == 0 and np.isnan(reg.evidence.relative_error()[0, 0])
    assert reg.evidence.sample_count[2, 2] == 1
    assert reg.evidence.flag_state.tolist() == [[False] * 3, [False] * 3, [False, False, True]]
    reg.evidence.reset()
    assert reg.evidence.sample_count.sum() == 0 and not reg.evidence.flag_state.any()


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
    reg.evidence.record(rows, cols, np.full(n, 2.0), np.full(n, 3.0), 0.5)  # +50 % everywhere
    reg.evidence.record([0, 0], [0, 5], [1.0, 1.0], [1.0, 1.0], 1.0)  # dilute two cells (still > 10 %)
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=1.0)

    regions = reg.evidence.flagged_regions(policy, connectivity=8)
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

    four = reg.evidence.flagged_regions(policy, connectivity=4)
    assert sorted(r.cell_count for r in four) == [1, 1, 1, 5]
    big_only = reg.evidence.flagged_regions(UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=1.0,
                                                min_region_cells=2))
    assert [r.cell_count for r in big_only] == [5, 2]
    # regions without georeferencing carry no world coordinates
    plain = registry((2, 2))
    plain.evidence.record([0], [0], [1.0], [2.0], 1.0)
    (only,) = plain.evidence.flagged_regions(policy)
    assert only.representative_xy_m is None and only.bounds_m is None
    with pytest.raises(InvalidParameterError, match="connectivity must be 4 or 8"):
        reg.evidence.flagged_regions(policy, connectivity=6)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="policy must be an UpdatePolicy"):
        reg.evidence.flagged({"threshold_pct": 10})  # type: ignore[arg-type]


def test_relative_error_function_counts_zero_charges_and_empty_cells() -> None:
    err = relative_error([1.2, 0.0, 1.0, -1.0, 5.0], [1.0, 0.0, 0.0, 0.0, 2.0], [3, 1, 1, 1, 0])
    assert err[0] == pytest.approx(0.2) and err[1] == 0.0
    assert err[2] == np.inf and err[3] == -np.inf and np.isnan(err[4])


def test_evidence_of_changed_cells_is_forgotten_by_assign_only_there() -> None:
    reg = registry((2, 2))
    reg.evidence.record([0, 1], [0, 1], [1.0, 1.0], [2.0, 2.0], 1.0)
    reg.assign((np.array([0]), np.array([0])), reg.add_model(GainModel(2.0), name="m"))
    assert reg.evidence.sample_count.tolist() == [[0, 0], [0, 1]]
