"""Tests of energy.models.loading: model classes by name and load_current_model."""

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from energy.models import (
    MODEL_CLASSES,
    ConstantCurrentModel,
    CurrentModel,
    LinearCurrentModel,
    ModelRecord,
    PhysicsCurrentModel,
    VibrationCurrentEstimator,
    load_current_model,
    model_class,
    write_model_file,
)
from terrawatt_base.errors import FileFormatError


def _log() -> InteractionLog:
    t = np.arange(0.0, 20.0, 0.1)
    v = 0.5 + 0.3 * np.sin(t)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, v, np.zeros(t.size), 1.0 + 2.0 * v, 1.2 + 2.0 * v, ta, np.full(ta.size, 9.81),
                          meta=LogMeta(ground_label="g"))


def test_model_class_by_name():
    assert model_class("LinearCurrentModel") is LinearCurrentModel
    assert model_class("PhysicsCurrentModel") is PhysicsCurrentModel
    assert model_class("ConstantCurrentModel") is ConstantCurrentModel
    assert model_class("VibrationCurrentEstimator") is VibrationCurrentEstimator
    assert issubclass(model_class("AdaptedCurrentModel"), CurrentModel)
    assert model_class("Forest") is None and model_class(3) is None
    assert set(MODEL_CLASSES) >= {"LinearCurrentModel", "VibrationCurrentEstimator", "AdaptedCurrentModel"}


def test_load_gives_back_the_saved_class_and_predictions(tmp_path):
    log = _log()
    for model in (LinearCurrentModel().fit(log), ConstantCurrentModel().fit(log)):
        back = load_current_model(model.save(tmp_path / f"{type(model).__name__}.zip"))
        assert type(back) is type(model)
        np.testing.assert_array_equal(back.predict(log), model.predict(log))


def test_a_file_of_an_unknown_class_is_a_file_format_error(tmp_path):
    path = write_model_file(tmp_path / "m.zip", ModelRecord("ForestCurrentModel", {}, {}))
    with pytest.raises(FileFormatError, match=r"m\.zip' holds an unknown model class 'ForestCurrentModel'; expected one of "
                                              r"\['ConstantCurrentModel'"):
        load_current_model(path)
    with pytest.raises(FileFormatError, match="does not exist or is not a file"):
        load_current_model(tmp_path / "missing.zip")
