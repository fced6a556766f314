"""One contract test run against every drive-current model (scikit-learn habit)."""

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from energy import (
    ConstantCurrentModel,
    CurrentModel,
    InteractionLog,
    LinearCurrentModel,
    LogMeta,
    PhysicsCurrentModel,
    VibrationCurrentEstimator,
    estimator_preset,
    load_current_model,
)
from energy.models import CURRENT_MODEL_FORMAT_VERSION
from terrawatt_base.errors import FileFormatError, FormatVersionError, InvalidParameterError, NotFittedError

LEGACY = Path(__file__).resolve().parents[1] / "fixtures" / "current_models_v1"


def _header(path: Path) -> dict:
    with zipfile.ZipFile(path) as archive:
        return json.loads(archive.read("model.json"))


def _forge(path: Path, change) -> None:
    """Rewrite the model.json of a saved model with ``change(header)`` (arrays kept)."""
    with zipfile.ZipFile(path) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    header = json.loads(entries["model.json"])
    change(header)
    entries["model.json"] = json.dumps(header).encode()
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in entries.items():
            archive.writestr(name, data)


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
    assert _header(path)["format_version"] == CURRENT_MODEL_FORMAT_VERSION


def test_wrong_version_raises_format_version_error(make, data, tmp_path):
    path = make().fit(data[0]).save(tmp_path / "model.pt")
    _forge(path, lambda h: h.update(format_version=CURRENT_MODEL_FORMAT_VERSION + 1))
    with pytest.raises(FormatVersionError, match=f"version {CURRENT_MODEL_FORMAT_VERSION + 1}.*reads versions"):
        load_current_model(path)
    # a version-1 (torch) checkpoint that claims another version is refused the same way
    payload = {"format": "terrawatt-current-model", "format_version": 7, "model_class": "ConstantCurrentModel",
               "params": {}, "state": {"current_a": [1.0, 2.0]}}
    torch.save(payload, tmp_path / "old.pt")
    with pytest.raises(FormatVersionError, match="version 7.*expected 1"):
        load_current_model(tmp_path / "old.pt")


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


def test_same_seed_gives_the_same_weights_and_leaves_the_global_rng_alone(data):
    state = torch.get_rng_state()
    a, b = _tiny("default").fit(data[0]), _tiny("default").fit(data[0])
    assert torch.equal(torch.get_rng_state(), state)  # seeded through local generators only
    for net_a, net_b in zip(a.networks_, b.networks_):
        for (ka, wa), (kb, wb) in zip(net_a.state_dict().items(), net_b.state_dict().items()):
            assert ka == kb and torch.equal(wa, wb)
    c = VibrationCurrentEstimator(a.config, seed=4).fit(data[0])
    assert not torch.equal(c.networks_[0].window_in.weight, a.networks_[0].window_in.weight)


@pytest.mark.parametrize("name", ["constant", "linear", "physics", "estimator"])
def test_version_1_torch_checkpoints_still_load(name, data):
    # files written by the previous release (torch.save of every model class)
    model = load_current_model(LEGACY / f"{name}.pt")
    expected = np.load(LEGACY / "predictions.npz")[name]
    assert np.array_equal(model.predict(data[1]), expected)


FORGERIES = {
    "missing state": lambda h: h.pop("state"),
    "missing model_class": lambda h: h.pop("model_class"),
    "state of another shape": lambda h: h["state"].clear(),
    "params not a dict": lambda h: h.update(params=[1, 2]),
    "state not a dict": lambda h: h.update(state="weights"),
    "class name not a model": lambda h: h.update(model_class="InteractionLog"),
    "class name of the base": lambda h: h.update(model_class="CurrentModel"),
    "class name not a string": lambda h: h.update(model_class=["LinearCurrentModel"]),
    "forged parameter": lambda h: h["params"].update(colour="red"),
    "format of another kind": lambda h: h.update(format="something-else"),
}


@pytest.mark.parametrize("forgery", sorted(FORGERIES))
@pytest.mark.parametrize("kind", ["linear", "physics", "estimator-default"])
def test_forged_files_raise_file_format_error(forgery, kind, data, tmp_path):
    path = MODELS[kind]().fit(data[0]).save(tmp_path / "model.pt")
    _forge(path, FORGERIES[forgery])
    with pytest.raises(FileFormatError):
        load_current_model(path)


def test_forged_values_inside_the_state_raise_file_format_error(data, tmp_path):
    est = _tiny("default").fit(data[0])
    forgeries = [
        lambda h: h["state"].update(rate_hz="fast"),
        lambda h: h["state"]["normalisers"].pop("v"),
        lambda h: h["state"].update(weights=[{"window_in.weight": [[1.0]]}]),
        lambda h: h["state"].update(weights=[]),
        lambda h: h["state"]["weights"][0].update(extra={"__array__": "arrays/999.npy"}),
        lambda h: h["state"]["config"].update(n_members="five"),
        lambda h: h["state"].update(physics={"params": {}, "state": {}}),
        lambda h: h["params"].update(seed=-3),
    ]
    for i, forge in enumerate(forgeries):
        path = est.save(tmp_path / f"m{i}.pt")
        _forge(path, forge)
        with pytest.raises(FileFormatError):
            load_current_model(path)
    path = LinearCurrentModel().fit(data[0]).save(tmp_path / "lin.pt")
    _forge(path, lambda h: h["state"].update(coef=[["a"] * 2] * 4))
    with pytest.raises(FileFormatError, match="LinearCurrentModel"):
        load_current_model(path)
    _forge(path, lambda h: h["state"].update(coef=[[float("nan")] * 2] * 4))
    with pytest.raises(FileFormatError, match="NaN"):
        load_current_model(path)


def _leaf_paths(value, path=()):
    """Paths to every plain leaf and list of a model.json section (array references excluded)."""
    if isinstance(value, dict):
        if set(value) == {"__array__"}:
            return
        for k, v in value.items():
            yield from _leaf_paths(v, (*path, k))
    elif isinstance(value, list):
        if path:
            yield path
        for i, v in enumerate(value):
            yield from _leaf_paths(v, (*path, i))
    elif path:
        yield path


def test_a_value_of_another_kind_anywhere_in_the_file_is_refused(data, tmp_path):
    # a list where a flag, a name, a number or a mapping belongs loaded before (bool([..]) and
    # str([..]) accept anything): every plain entry of every section is replaced in turn by a
    # list of numbers (where a single value belongs) and by a list of lists of strings, which
    # is no valid value anywhere in the format
    est = _tiny("default").fit(data[0])
    from energy.models import fit_interval

    models = {"estimator": est, "linear": fit_interval(LinearCurrentModel(), data[0], folds=2)}
    models["adapted"] = models["linear"].adapt(data[1], method="bayes", scope="run")
    for kind, model in models.items():
        saved = model.save(tmp_path / f"{kind}.zip")
        header = _header(saved)
        paths = [(section, p) for section in ("params", "state", "trained_on", "interval")
                 for p in _leaf_paths(header.get(section))]
        assert len(paths) > 10, kind
        for section, path in paths:
            node = header[section]
            for key in path:
                node = node[key]
            for value in ([["x"], ["y"]], *([] if isinstance(node, list) else [[1.0, 2.0]])):
                forged = tmp_path / f"{kind}-forged.zip"
                forged.write_bytes(saved.read_bytes())

                def change(h, section=section, path=path, value=value):
                    node = h[section]
                    for key in path[:-1]:
                        node = node[key]
                    node[path[-1]] = value

                _forge(forged, change)
                with pytest.raises(FileFormatError):
                    load_current_model(forged)
                    pytest.fail(f"{kind}: {section}{list(path)} = {value!r} loaded")


def test_truncated_random_and_foreign_files_raise_file_format_error(data, tmp_path):
    path = _tiny("default").fit(data[0]).save(tmp_path / "model.pt")
    raw = path.read_bytes()
    rng = np.random.default_rng(0)
    for cut in (0, 10, len(raw) // 3, len(raw) - 5):
        path.write_bytes(raw[:cut])
        with pytest.raises(FileFormatError):
            load_current_model(path)
    path.write_bytes(rng.bytes(4096))
    with pytest.raises(FileFormatError, match="not a readable"):
        load_current_model(path)
    with zipfile.ZipFile(path, "w") as archive:  # a valid zip of something else
        archive.writestr("readme.txt", "hello")
    with pytest.raises(FileFormatError, match="not a terrawatt current-model file"):
        load_current_model(path)
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("model.json", "[" * 100_000)
    with pytest.raises(FileFormatError):
        load_current_model(path)
    with pytest.raises(FileFormatError, match="does not exist"):
        load_current_model(tmp_path)


def test_saving_onto_a_directory_or_under_a_file_is_a_library_error(data, tmp_path):
    model = LinearCurrentModel().fit(data[0])
    (tmp_path / "folder").mkdir()
    with pytest.raises(InvalidParameterError, match="is a directory"):
        model.save(tmp_path / "folder")
    (tmp_path / "file").write_text("x")
    with pytest.raises(InvalidParameterError, match="which is a file"):
        model.save(tmp_path / "file" / "model.pt")


def test_temporaries_of_a_killed_save_are_removed_by_the_next_save_or_load(data, tmp_path):
    target = tmp_path / "model.pt"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f".model.pt.{int(dead.stdout)}.abc123.tmp"
    stale.write_bytes(b"half a model")
    LinearCurrentModel().fit(data[0]).save(target)
    assert not stale.exists()
    stale.write_bytes(b"half a model")
    load_current_model(target)
    assert not stale.exists()


def test_baselines_and_loading_never_import_torch(data, tmp_path):
    path = LinearCurrentModel().fit(data[0]).save(tmp_path / "linear.pt")
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'torch':\n"
        "            raise ImportError('torch is blocked')\n"
        "sys.meta_path.insert(0, Block())  # any torch import now fails\n"
        "import energy\n"
        "from energy import ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel, load_current_model\n"
        f"model = load_current_model({str(path)!r})\n"
        "assert type(model).__name__ == 'LinearCurrentModel'\n"
        "assert 'torch' not in sys.modules\n"
        "print('ok')\n"
    )
    env = dict(os.environ, MPLBACKEND="Agg")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=Path(__file__).resolve().parents[2])
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr
