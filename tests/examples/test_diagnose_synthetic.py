"""The diagnosis example runs (quick): it names turning resistance and the gap shrinks."""

import importlib.util
import json
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "diagnose_synthetic.py"


def test_diagnose_synthetic_quick(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("diagnose_synthetic_example", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    numbers = mod.main(["--quick", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "turning_resistance (physics) explains" in out
    assert numbers["best"] == "turning_resistance"
    assert numbers["chosen"].split(",")[0] == "turning_resistance"
    assert numbers["shrink_pct"] > 80.0
    assert abs(numbers["before_charge_error_pct"]) > 50.0
    assert abs(numbers["after_charge_error_pct"]) < 5.0
    assert numbers["after_rmse_a"] < 0.5 * numbers["before_rmse_a"]
    written = json.loads((tmp_path / "diagnosis.json").read_text())
    assert written["chosen"][0] == "turning_resistance"
    assert (tmp_path / "diagnosis.md").read_text().startswith("# Sim-to-real gap diagnosis")
