"""The ``terrawatt reach`` command (terrawatt_cli.reach): raster, JSON and plot; GeoTIFF; bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_samples import PNG_MAGIC

import terrain
from planner import Reachability
from terrawatt_cli import main


# ---------------------------------------------------------------- CLI
def test_cli_writes_raster_json_and_plot_and_prints_the_figures(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    out = tmp_path / "out"
    rc = main(["reach", "--map", str(path), "--depot", "5.5", "5.5", "--battery-ah", "0.05", "--voltage", "24",
               "--reserve", "10", "--round-trip", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "reachable area" in text and "max round-trip energy" in text
    data = json.loads((out / "reach.json").read_text())
    assert data["budget_j"] == pytest.approx(0.05 * 24 * 3600) and data["reserve_j"] == pytest.approx(432.0)
    reach = Reachability.load(out / "reach.npz")
    assert data["reachable_cells"] == int(reach.reachable.sum()) > 0
    assert f"{data['reachable_area_m2']:,.0f} m^2" in text
    assert (out / "reach.png").read_bytes()[:8] == PNG_MAGIC
    assert not (out / "reach.tif").exists()


def test_cli_on_a_geotiff_writes_a_geotiff(tmp_path, capsys, wall_map):
    pytest.importorskip("rasterio", reason="GeoTIFF maps need the geo extra (rasterio)")
    tmap = wall_map.copy()
    tmap.crs = "EPSG:32633"
    dem = terrain.write_geotiff(tmap, tmp_path / "dem.tif")
    rc = main(["reach", "--map", str(dem), "--depot", "5.5", "5.5", "--battery-ah", "1", "--out", str(tmp_path / "o")])
    capsys.readouterr()
    assert rc == 0 and (tmp_path / "o" / "reach.tif").is_file() and not (tmp_path / "o" / "reach.npz").exists()


def test_cli_exits_1_when_no_cell_is_reachable(tmp_path, capsys):
    rc = main(["reach", "--example", "--depot", "10.3", "10.3", "--battery-ah", "1e-9", "--out", str(tmp_path)])
    assert rc == 1
    assert "no cell is reachable" in capsys.readouterr().out
    assert json.loads((tmp_path / "reach.json").read_text())["reachable_cells"] == 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--battery-ah", "-1"], "--battery-ah must be a number > 0"),
        (["--battery-ah", "1", "--reserve", "100"], "--reserve must be a percentage in [0, 100)"),
        (["--battery-ah", "1", "--voltage", "0"], "--voltage must be a number > 0"),
        (["--battery-ah", "1", "--depot", "500", "5"], "outside the map"),
        (["--battery-ah", "1", "--depot", "nan", "5"], "--depot must be two finite coordinates"),
        (["--battery-ah", "1", "--max-slope-deg", "95"], "--max-slope-deg"),
        (["--battery-ah", "1", "--robot", "tank"], "tank"),
    ],
)
def test_cli_bad_input_exits_2_with_one_line(tmp_path, capsys, extra, message):
    rc = main(["reach", "--example", "--out", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "o" / "reach.json").exists()


def test_cli_map_needs_a_depot_and_a_free_one(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    assert main(["reach", "--map", str(path), "--battery-ah", "1", "--out", str(tmp_path / "o")]) == 2
    assert "--depot X Y is required with --map" in capsys.readouterr().err
    assert main(["reach", "--map", str(path), "--depot", "20.5", "5", "--battery-ah", "1",
                 "--out", str(tmp_path / "o")]) == 2
    assert "blocked cell" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["reach", "--example", "--battery-ah", "1", "--out", str(tmp_path / "file")]) == 2
    assert "--out" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["reach", "--example", "--map", str(path), "--battery-ah", "1"])
    assert exc.value.code == 2
    capsys.readouterr()


def test_cli_missing_map_file_exits_2(tmp_path, capsys):
    rc = main(["reach", "--map", str(Path(tmp_path) / "nope.npz"), "--depot", "1", "1", "--battery-ah", "1",
               "--out", str(tmp_path / "o")])
    assert rc == 2
    assert "nope.npz" in capsys.readouterr().err
