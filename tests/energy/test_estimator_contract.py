"""One contract test run against every drive-current model (scikit-learn habit)."""

import numpy as np
import pytest
import torch

from energy import (
    CURRENT_MODEL_FORMAT_VERSION,
    ConstantCurrentModel,
    CurrentModel,
    FileFormatError,
    FormatVersionError,
    InteractionLog,
    LinearCurrentModel,
    LogMeta,
    NotFittedError,
    PhysicsCurrentModel,
    VibrationCurrentEstimator,
    estimator_preset,
    load_current_model,
)


def _log(seed: int, duration_s: float = 30.0, drive_hz: float = 10.0) -> InteractionLog:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / drive_hz)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    v = 0.45 + 0.35 * np.sin(2 * np.pi * t / 7.0 + p1)
    w = 0.5 * np.sin(2 * np.pi * t / 5.0 + p2)
    left = 0.6 + 4.0 * np.abs(v) + 3.0 * np.maximum(-w, 0) + np.maximum(w, 0) + 0.05 * rng.standard_normal(t.size)
    right = 0.6 + 4.0 * np.abs(v) + 3.0 * np.maximum(w, 0) + np.maximum(-w, 0) + 0.05 * rng.standard_normal(t.size)
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    az = 9.81 + 0.4 * rng.standard_normal(ta.size)
    return InteractionLog(t, v, w, left, right, ta, az, meta=LogMeta(source=f"synthetic-{seed}", ground_label="synthetic",
                                                                    velocity_source="measured", track_width_m=0.555))


def _tiny(preset: str) -> VibrationCurrentEstimator:
    if preset == "paper":
        cfg = estimator_preset("paper").replace(max_epochs=3, n_spectrum_bins=400, hidden_sizes=(16, 16, 16))
    else:
        cfg = estimator_preset("default").replace(max_epochs=8, n_members=2, hidden_sizes=(16,), patience=3)
    return VibrationCurrentEstimator(cfg, seed=3)


MODELS = {
    "constant": lambda: ConstantCurrentModel(),
    "linear": lambda: LinearCurrentModel(),
    "physics": lambda: PhysicsCurrentModel(),
    "estimator-default": lambda: _tiny("default"),
    "estimator-paper": lambda: _tiny("paper"),
}


@pytest.fixture(scope="module")
def data():
    return [_log(0), _log(1)], _log(2)


@pytest.fixture(params=sorted(MODELS))
def make(request):
    return MODELS[request.param]


def test_unfitted_model_refuses_to_predict_score_or_save(make, data, tmp_path):
    model = make()
    assert isinstance(model, CurrentModel) and not model.is_fitted
    with pytest.raises(NotFittedError, match="not fitted"):
        model.predict(data[1])
    with pytest.raises(NotFittedError, match="not fitted"):
        model.score(data[1])
    with pytest.raises(NotFittedError, match="not fitted"):
        model.save(tmp_path / "m.pt")
    with pytest.raises(ValueError):  # NotFittedError is also a ValueError, as in scikit-learn
        model.predict(data[1])


def test_fit_returns_self_sets_only_underscore_attributes(make, data):
    model = make()
    before = dict(vars(model))
    params = model.get_params()
    assert model.fit(data[0]) is model
    new = set(vars(model)) - set(before)
    assert new and all(k.endswith("_") for k in new)
    assert model.get_params() == params
    pred = model.predict(data[1])
    assert pred.shape == (len(data[1]), 2) and np.all(np.isfinite(pred))
    assert isinstance(model.score(data[1]), float)


def test_clone_is_unfitted_with_same_params(make, data):
    model = make().fit(data[0])
    twin = model.clone()
    assert type(twin) is type(model) and not twin.is_fitted
    assert twin.get_params() == model.get_params()


def test_same_seed_gives_same_predictions(make, data):
    a = make().fit(data[0]).predict(data[1])
    b = make().fit(data[0]).predict(data[1])
    assert np.array_equal(a, b)


def test_save_load_round_trip_gives_identical_predictions(make, data, tmp_path):
    model = make().fit(data[0])
    path = model.save(tmp_path / "model.pt")
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]  # atomic write cleaned up
    again = load_current_model(path)
    assert type(again) is type(model)
    assert np.array_equal(again.predict(data[1]), model.predict(data[1]))
    same = type(model).load(path)
    assert np.array_equal(same.predict(data[1]), model.predict(data[1]))
    assert torch.load(path, map_location="cpu", weights_only=True)["format_version"] == CURRENT_MODEL_FORMAT_VERSION


def test_wrong_version_raises_format_version_error(make, data, tmp_path):
    path = make().fit(data[0]).save(tmp_path / "model.pt")
    payload = torch.load(path, map_location="cpu", weights_only=True)
    payload["format_version"] = CURRENT_MODEL_FORMAT_VERSION + 1
    torch.save(payload, path)
    with pytest.raises(FormatVersionError, match="version"):
        load_current_model(path)


def test_corrupt_file_raises_file_format_error(make, data, tmp_path):
    path = make().fit(data[0]).save(tmp_path / "model.pt")
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(FileFormatError, match="not a readable"):
        load_current_model(path)
    path.write_bytes(b"not a model at all")
    with pytest.raises(FileFormatError):
        load_current_model(path)
    with pytest.raises(FileFormatError, match="does not exist"):
        load_current_model(tmp_path / "missing.pt")


def test_loading_into_the_wrong_class_is_refused(data, tmp_path):
    path = ConstantCurrentModel().fit(data[0]).save(tmp_path / "c.pt")
    with pytest.raises(FileFormatError, match="not a LinearCurrentModel"):
        LinearCurrentModel.load(path)
