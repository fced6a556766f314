"""The adaptive-mission example runs (quick) and prints its numbers."""

import importlib.util
import math
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "adaptive_mission.py"


def test_adaptive_mission_quick(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("adaptive_mission_example", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    numbers = mod.main(["--quick", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "error_without_updates_pct" in out
    assert numbers["status"] == "completed"
    assert numbers["updates"] >= 1
    assert abs(numbers["error_without_updates_pct"]) > 15.0
    assert abs(numbers["error_after_update_pct"]) < abs(numbers["error_without_updates_pct"])
    assert abs(numbers["error_after_update_pct"]) < 5.0  # the target for the remaining route
    assert math.isfinite(numbers["saved_driving_only_wh"])
    assert (tmp_path / "mission.json").exists() and (tmp_path / "mission.png").exists()
