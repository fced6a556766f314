"""``terrawatt diagnose`` on CSV logs with battery voltage and pack current: the power stage in the files and the printout."""

from __future__ import annotations

import dataclasses
import json

from diagnosis_scenarios import scenario

from energy import write_csv_log
from terrawatt_cli import main


def test_power_logs_add_the_power_stage(tmp_path, capsys):
    sc = dataclasses.replace(scenario("control"), n_runs=3, run_duration_s=8.0)
    (tmp_path / "logs").mkdir()
    for k, log in enumerate(sc.make_logs(0)):
        write_csv_log(log, tmp_path / "logs" / f"run_{k}.csv")
    rc = main(["diagnose", "--model", "physics", "--ground", "coated_wood", "--data", str(tmp_path / "logs"),
               "--out", str(tmp_path / "out"), "--quiet", "--effects", "idle_current", "sensor", "control"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text())
    # the physics current model has no electronics: the power stage adds them
    assert doc["power"]["chosen"] and set(doc["power"]["chosen"]) <= {"sensor", "control"}
    assert "battery power (voltage x pack current):" in out.out and "energy err %" in out.out
    assert "Not identifiable from current logs" not in out.out
    assert "## Battery power: electrical candidates" in (tmp_path / "out" / "diagnosis.md").read_text()
