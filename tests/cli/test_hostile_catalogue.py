"""The hostile-input catalogue of the fourth round, re-run through the CLI as a user would: each input is a clear error.

Each case is one command line from the round's list (the memory-budget variable, Monte Carlo counts,
risk levels, adapt flags, robot files, map frame origins, lon/lat outside a projection, output
folders holding the user's files). The property for every one: exit 2, exactly one line on stderr
naming the input, no traceback, no "internal error", and no file of the user's deleted or changed.
Cases that need a prepared model, land cover or logs have their own tests beside their readers.
"""

from __future__ import annotations

import json

import pytest

from terrawatt_cli import EXIT_BAD_INPUT, main

PLAN = ["plan", "--map", "example", "--start", "10", "10", "--goal", "150", "150", "--planner", "lattice"]
MISSION = ["mission", "--battery-ah", "20"]


def _robot_file(tmp_path, **changes):
    from energy import robot_preset
    from energy.params import write_robot_file

    path = write_robot_file(robot_preset("husky"), tmp_path / "robot.json")
    doc = json.loads(path.read_text())
    doc.update(changes)
    path.write_text(json.dumps(doc))
    return str(path)


CASES = [
    # the memory-budget variable: never silently the default
    ("budget 0", PLAN, {"TERRAWATT_MEMORY_BUDGET_BYTES": "0"}, "TERRAWATT_MEMORY_BUDGET_BYTES"),
    ("budget abc", PLAN, {"TERRAWATT_MEMORY_BUDGET_BYTES": "abc"}, "TERRAWATT_MEMORY_BUDGET_BYTES"),
    ("budget 1e30", PLAN, {"TERRAWATT_MEMORY_BUDGET_BYTES": "1e30"}, "TERRAWATT_MEMORY_BUDGET_BYTES"),
    # sizes from users, checked before allocation
    ("monte carlo 1e9", [*MISSION, "--monte-carlo", "1000000000"], {}, "missions"),
    ("monte carlo 1e30", [*MISSION, "--monte-carlo", str(10**30)], {}, "missions"),
    # a risk level below the median plans on luck
    ("risk 1e-9", [*PLAN, "--risk", "1e-9"], {}, "--risk 1e-09 lies below the median"),
    ("risk 1.5", [*PLAN, "--risk", "1.5"], {}, "--risk must be"),
    # flags that were silently ignored
    ("adapt seconds with loo", ["evaluate", "--data", "{logs}", "--adapt-seconds", "20"], {},
     "--adapt-seconds applies to --protocol adapt or few-shot"),
    ("adapt seconds 5", ["evaluate", "--data", "{logs}", "--protocol", "few-shot", "--adapt-seconds", "5"], {},
     "the update needs more than 5 s"),
    # a frame origin no map is near
    ("frame origin 1e308", [*PLAN, "--nav2-map", "{tmp}/nav2/", "--map-frame-origin", "1e308", "0"], {}, "--map-frame-origin"),
    # robot files: a format version that is not an integer
    ("robot version 1.9", [*PLAN, "--robot", "{robot:format_version=1.9}"], {}, "no valid format version (an integer; got 1.9)"),
    ("robot version true", [*PLAN, "--robot", "{robot:format_version=true}"], {}, "(an integer; got True)"),
]


@pytest.mark.parametrize(("label", "argv", "env", "expected"), CASES, ids=[c[0] for c in CASES])
def test_every_hostile_input_is_one_clear_line_and_exit_2(tmp_path, capsys, monkeypatch, label, argv, env, expected):
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "mine.txt").write_text("the user's own file\n")
    out = tmp_path / "out"
    out.mkdir()
    keep = out / "leg_0042.csv"
    keep.write_text("the user's own leg\n")
    args = []
    for a in argv:
        if a.startswith("{robot:"):
            key, value = a[len("{robot:"):-1].split("=")
            a = _robot_file(tmp_path, **{key: json.loads(value)})
        args.append(a.replace("{logs}", str(logs)).replace("{tmp}", str(tmp_path)))
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    rc = main([*args, "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == EXIT_BAD_INPUT, (label, err)
    assert err.count("\n") == 1 and "Traceback" not in err and "internal error" not in err, err
    assert expected in err, err
    assert keep.read_text() == "the user's own leg\n" and (logs / "mine.txt").exists()
