"""Tests of planner.registry: the model table, grid binding, assignments, updates and rollback."""

from __future__ import annotations

import numpy as np
import pytest
from registry_models import GainModel, cell_predictions, registry

from planner.registry import CellModelRegistry, CurrentModelProtocol, UpdatePolicy
from terrain import GridMismatchError, InvalidParameterError, OutOfBoundsError, TerrainMap, UnknownNameError


# ------------------------------------------------------------------- model table
def test_protocol_and_model_table() -> None:
    reg = registry()
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
    reg = registry()
    view = reg.model_id_map
    with pytest.raises(ValueError):
        view[0, 0] = 5
    reg.assign(np.ones((4, 5), bool), reg.add_model(GainModel(2.0), name="m"))
    assert np.all(view == 0) and np.all(reg.model_id_map == 1)


def test_model_table_errors() -> None:
    reg = registry()
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
        reg.evidence.reset(np.ones((4, 4), bool))


# -------------------------------------------------------------------- updates
def test_worse_model_is_rejected_and_old_one_kept() -> None:
    reg = registry()
    policy = UpdatePolicy(threshold_pct=10.0, min_samples=1, hysteresis_pct=2.0)
    reg.evidence.record([1, 1], [1, 2], [1.0, 1.0], [2.0, 2.0], 1.0)
    (region,) = reg.evidence.flagged_regions(policy)
    before = reg.model_id_map
    for err_new in (0.30, 0.20):  # worse, then equal: both rejected
        decision = reg.propose_update(region, GainModel(9.0), err_new, 0.20, name="snow-v1", reason="test")
        assert not decision.accepted and decision.model_id is None and decision.version is None
        assert decision.improvement == pytest.approx(0.20 - err_new) and decision.cell_count == 2
    np.testing.assert_array_equal(reg.model_id_map, before)
    assert reg.history == [] and reg.model_ids == (0,)
    assert reg.evidence.sample_count.sum() == 2 and reg.evidence.flag_state.sum() == 2  # evidence untouched
    assert reg.model_for(1, 1) is reg.model(0)

    better = GainModel(1.5)
    decision = reg.propose_update(region, better, 0.05, 0.20, name="snow-v1", reason="error 100 %",
                                  meta={"ground": "snow"})
    assert decision.accepted and decision.model_id == 1 and decision.version == 1
    assert decision.improvement == pytest.approx(0.15)
    assert reg.model_for(1, 1) is better and reg.model_for(1, 2) is better
    assert int(np.count_nonzero(reg.model_id_map == 1)) == 2
    assert reg.evidence.sample_count.sum() == 0 and not reg.evidence.flag_state.any()  # evidence reset in the region
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
    reg = registry()
    with pytest.raises(InvalidParameterError, match=match):
        reg.propose_update(np.ones((4, 5), bool), GainModel(), *errors, name="m", reason="r")
    assert reg.model_ids == (0,)


def test_propose_update_rejects_empty_region_and_duplicate_name() -> None:
    reg = registry()
    with pytest.raises(InvalidParameterError, match="region selects no cell"):
        reg.propose_update(np.zeros((4, 5), bool), GainModel(), 0.1, 0.2, name="m", reason="r")
    with pytest.raises(InvalidParameterError, match="already in the registry"):
        reg.propose_update(np.ones((4, 5), bool), GainModel(), 0.1, 0.2, name="physics", reason="r")


def test_rollback_restores_exact_assignment_and_predictions() -> None:
    reg = registry((4, 5))
    initial_pred = cell_predictions(reg)
    m1 = reg.add_model(GainModel(2.0, 0.1), name="sand")
    left = np.zeros((4, 5), bool)
    left[:, :3] = True
    v1 = reg.assign(left, m1, reason="known sand")
    after_v1_map = reg.model_id_map
    after_v1_pred = cell_predictions(reg)
    top = np.zeros((4, 5), bool)
    top[2:, 1:] = True  # overlaps sand cells and prior cells
    d = reg.propose_update(top, GainModel(3.0, -0.2), 0.04, 0.3, name="snow", reason="flagged")
    assert d.accepted and reg.version == 2
    assert not np.array_equal(cell_predictions(reg), after_v1_pred)

    undone = reg.rollback()
    assert [u.version for u in undone] == [2]
    np.testing.assert_array_equal(reg.model_id_map, after_v1_map)
    np.testing.assert_array_equal(cell_predictions(reg), after_v1_pred)
    assert reg.version == v1.version == 1

    # a new change after a rollback gets a fresh version number
    v3 = reg.assign((np.array([0]), np.array([4])), reg.model_id("snow"))
    assert v3.version == 3 and [v.version for v in reg.history] == [1, 3]
    undone = reg.rollback(version=0)
    assert [u.version for u in undone] == [3, 1]
    assert np.all(reg.model_id_map == 0) and reg.history == []
    np.testing.assert_array_equal(cell_predictions(reg), initial_pred)
    assert reg.model_ids == (0, 1, 2)  # models stay in the table

    with pytest.raises(InvalidParameterError, match="nothing to roll back"):
        reg.rollback()
    reg.assign(left, m1)
    with pytest.raises(InvalidParameterError, match="version must be 0 or one of"):
        reg.rollback(version=2)


def test_rollback_to_a_middle_version_and_evidence_reset() -> None:
    reg = registry((3, 3))
    ids = [reg.add_model(GainModel(float(k)), name=f"m{k}") for k in (2, 3, 4)]
    maps = [reg.model_id_map]
    for k, mid in enumerate(ids):
        mask = np.zeros((3, 3), bool)
        mask[: k + 1, : k + 1] = True
        reg.assign(mask, mid)
        maps.append(reg.model_id_map)
    reg.evidence.record([0, 2, 1], [0, 2, 2], [1.0, 1.0, 1.0], [1.5, 1.5, 1.5], 1.0)
    reg.rollback(version=2)
    np.testing.assert_array_equal(reg.model_id_map, maps[2])
    # (2, 2) and (1, 2) changed model (m4 -> prior / m3): evidence reset; (0, 0) changed m4 -> m3
    assert reg.evidence.sample_count.sum() == 0
    reg.evidence.record([0, 1], [0, 0], [1.0, 1.0], [1.5, 1.5], 1.0)
    reg.rollback(version=1)
    np.testing.assert_array_equal(reg.model_id_map, maps[1])
    assert reg.evidence.sample_count[0, 0] == 0 and reg.evidence.sample_count[1, 0] == 0  # both changed m3 -> m2 / prior
    reg.evidence.record([0], [0], [1.0], [1.5], 1.0)
    reg.assign((np.array([0]), np.array([0])), ids[0])  # same model as before: evidence kept
    assert reg.evidence.sample_count[0, 0] == 1


def test_georeferencing_goes_through_grid() -> None:
    tmap = TerrainMap(np.zeros((4, 5)), cell_size_m=2.0, origin_xy_m=(10.0, 20.0))
    reg = CellModelRegistry.from_terrain(tmap, GainModel())
    assert reg.grid == tmap.grid
    assert registry().grid is None and registry().cell_size_m is None and registry().origin_xy_m is None
    with pytest.raises(InvalidParameterError, match="no finite far corner"):
        CellModelRegistry((3, 3), GainModel(), cell_size_m=1e308, origin_xy_m=(0.0, 0.0))
    with pytest.raises(InvalidParameterError, match=r"cell_size_m must be a real number, got '1.0' \(str\)"):
        CellModelRegistry((3, 3), GainModel(), cell_size_m="1.0", origin_xy_m=(0.0, 0.0))
    with pytest.raises(InvalidParameterError, match="shape must be"):
        CellModelRegistry((2.0, 3), GainModel())
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        CellModelRegistry.from_terrain("map.npz", GainModel())  # type: ignore[arg-type]


def test_rollback_rejects_a_version_that_is_not_an_integer() -> None:
    reg = registry()
    reg.assign(np.ones((4, 5), bool), reg.add_model(GainModel(2.0), name="m"))
    with pytest.raises(InvalidParameterError, match="version must be an integer"):
        reg.rollback(version="1")  # type: ignore[arg-type]
    assert reg.version == 1
