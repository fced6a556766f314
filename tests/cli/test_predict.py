"""The ``terrawatt predict`` command (terrawatt_cli.predict): a trained model round trip and a corrupt model file."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_samples import FIXTURES, is_png

from terrawatt_cli import main


def test_train_then_predict_round_trip(tmp_path, capsys):
    model = tmp_path / "linear.pt"
    assert main(["train", "--data", str(FIXTURES), "--model", "linear", "--out", str(model)]) == 0
    assert model.is_file()
    assert main(["predict", "--model", str(model), "--data", str(FIXTURES), "--out", str(tmp_path / "pred"),
                 "--plots"]) == 0
    figures = sorted(p.name for p in (tmp_path / "pred" / "plots").iterdir())
    assert figures == ["current_asphalt_pro_00.png", "current_snow_pro_05.png"]
    assert all(is_png(tmp_path / "pred" / "plots" / f) for f in figures)
    runs = json.loads((tmp_path / "pred" / "predictions.json").read_text())["runs"]
    assert {(r["ground"], r["side"]) for r in runs} == {(g, s) for g in ("asphalt", "snow") for s in ("left", "right")}
    for r in runs:
        assert r["charge_true_mah"] > 0 and np.isfinite(r["charge_predicted_mah"])
        assert r["whole_run_error_pct"] == pytest.approx(
            100.0 * abs(r["charge_predicted_mah"] - r["charge_true_mah"]) / r["charge_true_mah"], rel=1e-6
        )
    capsys.readouterr()


def test_predict_with_a_corrupt_model_file_is_an_error(tmp_path, capsys):
    bad = tmp_path / "model.pt"
    bad.write_bytes(b"\x00garbage")
    rc = main(["predict", "--model", str(bad), "--data", str(FIXTURES), "--out", str(tmp_path)])
    assert rc == 2
    assert "model.pt" in capsys.readouterr().err
