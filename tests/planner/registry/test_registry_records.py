"""planner.registry.records: the model protocol, the update policy and the registry's value types."""

from __future__ import annotations

import numpy as np
import pytest

from planner.registry import (
    PRIOR_MODEL_ID,
    CurrentModelProtocol,
    FlaggedRegion,
    ModelEntry,
    RegistryVersion,
    UpdatePolicy,
)
from terrain import InvalidParameterError


# ------------------------------------------------------------------------ protocol
class _FitPredict:
    def fit(self, *args, **kwargs):
        return self

    def predict(self, *args, **kwargs):
        return 0.0


class _PredictOnly:
    def predict(self, *args, **kwargs):
        return 0.0


def test_the_prior_is_model_zero():
    assert PRIOR_MODEL_ID == 0


def test_the_protocol_needs_fit_and_predict():
    assert isinstance(_FitPredict(), CurrentModelProtocol)
    assert not isinstance(_PredictOnly(), CurrentModelProtocol)
    assert not isinstance(3.0, CurrentModelProtocol)


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


def test_policy_default_values_and_is_frozen():
    p = UpdatePolicy()
    assert (p.threshold_pct, p.min_samples, p.hysteresis_pct, p.min_region_cells) == (10.0, 10, 2.0, 1)
    assert p.clear_below_pct == 8.0
    with pytest.raises(AttributeError):
        p.threshold_pct = 5.0  # type: ignore[misc]


def test_policy_is_keyword_only():
    with pytest.raises(TypeError):
        UpdatePolicy(10.0)  # type: ignore[misc]


# ----------------------------------------------------------------------- records
def test_a_model_record_has_empty_read_only_metadata_by_default():
    rec = ModelEntry(2, "snow")
    assert (rec.model_id, rec.name, dict(rec.meta)) == (2, "snow", {})
    with pytest.raises(TypeError):
        rec.meta["k"] = 1  # type: ignore[index]


def _version(**overrides):
    fields = dict(version=1, kind="assign", model_id=1, rows=np.array([0, 1]), cols=np.array([2, 3]),
                  previous_model_ids=np.array([0, 0], np.int32), cell_count=2, reason="sand")
    fields.update(overrides)
    return RegistryVersion(**fields)


def test_a_registry_version_holds_its_cells():
    v = _version(kind="update", validation_error_new=0.1, validation_error_old=0.3)
    assert v.cell_count == 2 and v.kind == "update" and v.validation_error_new == 0.1
    assert _version().validation_error_new is None and _version().validation_error_old is None


@pytest.mark.parametrize(
    "overrides",
    [{"cols": np.array([1])}, {"previous_model_ids": np.array([0], np.int32)}, {"cell_count": 3}],
)
def test_a_registry_version_whose_cells_disagree_is_refused(overrides):
    with pytest.raises(InvalidParameterError, match="rows, cols, previous_model_ids and cell_count must agree"):
        _version(**overrides)


def test_a_registry_version_of_an_unknown_kind_is_refused():
    with pytest.raises(InvalidParameterError, match="kind must be 'assign' or 'update', got 'delete'"):
        _version(kind="delete")


def test_a_flagged_region_gives_its_mask():
    region = FlaggedRegion(
        region_id=1, rows=np.array([0, 0, 1]), cols=np.array([1, 2, 2]), cell_count=3,
        bbox_rows_cols=(0, 1, 1, 2), representative_row_col=(0, 2), representative_xy_m=None, bounds_m=None,
        relative_error=0.2, sample_count=30, model_ids=(0,),
    )
    mask = region.mask((2, 4))
    assert mask.dtype == bool
    assert mask.tolist() == [[False, True, True, False], [False, False, True, False]]
