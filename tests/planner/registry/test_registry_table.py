"""planner.registry.table: models by id with unique names and checked metadata."""

from __future__ import annotations

import numpy as np
import pytest
from registry_models import GainModel

from planner.registry import ModelEntry
from planner.registry.table import ModelTable, check_meta
from terrain import InvalidParameterError, UnknownNameError


def test_check_meta_gives_a_read_only_mapping_of_plain_values():
    meta = check_meta({"ground": "snow", "epochs": np.int64(40), "lr": np.float32(0.5)})
    assert dict(meta) == {"ground": "snow", "epochs": 40, "lr": 0.5}
    assert type(meta["epochs"]) is int and type(meta["lr"]) is float
    with pytest.raises(TypeError):
        meta["x"] = 1  # type: ignore[index]
    assert dict(check_meta(None)) == {}


@pytest.mark.parametrize(
    ("meta", "match"),
    [
        ([("a", 1)], "meta must be a mapping of str to str/int/float"),
        ({"": 1}, "meta keys must be non-empty strings, got ''"),
        ({3: 1}, "meta keys must be non-empty strings, got 3"),
        ({"flag": True}, r"meta\['flag'\] must be a str, int or float, got True \(bool\)"),
        ({"w": None}, r"meta\['w'\] must be a str, int or float"),
        ({"w": float("inf")}, r"meta\['w'\] must be finite, got inf"),
    ],
)
def test_check_meta_refuses_bad_metadata(meta, match):
    with pytest.raises(InvalidParameterError, match=match):
        check_meta(meta)


def test_models_get_ids_in_the_order_added():
    table = ModelTable()
    physics, snow = GainModel(1.0), GainModel(3.0)
    assert table.add(physics, name="physics") == 0
    assert table.add(snow, name="snow", meta={"epochs": 40}) == 1
    assert len(table) == 2 and table.ids == (0, 1)
    assert table.model(1) is snow and table.model(np.int64(0)) is physics
    assert table.id_of("snow") == 1
    rec = table.record(1)
    assert isinstance(rec, ModelEntry) and (rec.model_id, rec.name, dict(rec.meta)) == (1, "snow", {"epochs": 40})
    assert [r.name for r in table] == ["physics", "snow"]


def test_check_new_adds_nothing():
    table = ModelTable()
    assert dict(table.check_new(GainModel(), "a", {"k": "v"})) == {"k": "v"}
    assert len(table) == 0


def test_adding_refuses_non_models_empty_and_duplicate_names():
    table = ModelTable()
    table.add(GainModel(), name="physics")
    with pytest.raises(InvalidParameterError, match=r"prior must have fit\(\) and predict\(\) methods .* got object"):
        table.check_new(object(), "x", None, what="prior")
    with pytest.raises(InvalidParameterError, match="name"):
        table.add(GainModel(), name="")
    with pytest.raises(InvalidParameterError, match="a model named 'physics' is already in the registry"):
        table.add(GainModel(), name="physics")
    assert len(table) == 1


@pytest.mark.parametrize("bad", [5, -1, True, "0", 0.0])
def test_unknown_ids_are_refused(bad):
    table = ModelTable()
    table.add(GainModel(), name="physics")
    with pytest.raises(UnknownNameError, match=r"no model with id .*; known ids: \[0\]"):
        table.check_id(bad)
    with pytest.raises(UnknownNameError, match="no model with id"):
        table.model(bad)
    with pytest.raises(UnknownNameError, match="no model with id"):
        table.record(bad)


def test_an_unknown_name_is_refused_listing_the_known_ones():
    table = ModelTable()
    table.add(GainModel(), name="physics")
    with pytest.raises(UnknownNameError, match=r"no model named 'snow'; known: \['physics'\]"):
        table.id_of("snow")
