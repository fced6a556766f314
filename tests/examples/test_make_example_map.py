"""examples/make_example_map.py runs and rebuilds the bundled example map exactly."""

import importlib.util
from pathlib import Path

import numpy as np

from terrain import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, TerrainMap, example_map

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "make_example_map.py"


def test_script_rebuilds_the_bundled_map(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("make_example_map_example", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "example_map.npz"
    assert mod.main(["--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    rebuilt, bundled = TerrainMap.load(out), example_map()
    assert rebuilt.same_grid(bundled)
    assert rebuilt.ground_names == bundled.ground_names
    for layer in ("elevation", "ground", "obstacle"):
        np.testing.assert_array_equal(rebuilt[layer], bundled[layer], err_msg=layer)
    for xy in (EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M):
        assert not rebuilt.sample("obstacle", *xy)
