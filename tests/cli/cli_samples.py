"""Shared inputs and checks of the CLI tests: the BorealTC fixture logs, a small patch map, PNG and one-line-error checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import terrain

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def is_png(path: Path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == PNG_MAGIC


def patch_map(tmp_path: Path) -> Path:
    """Level asphalt with a sand band across the straight line."""
    ground = np.zeros((24, 60), dtype=int)
    ground[6:18, 20:40] = 1
    tmap = terrain.TerrainMap(np.zeros((24, 60)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    return tmap.save(tmp_path / "patch.npz")


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("terrawatt: error: ") and "Traceback" not in err and err.count("\n") == 1, err
    return err
