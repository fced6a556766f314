"""Tests of planner.batch_result: BatchRow and BatchResult check themselves, write CSV and JSON, show a table."""

from __future__ import annotations

import csv
import json
import math

import pytest
from batch_samples import EAST, ON_WALL, PAIRS, cost  # noqa: F401  (fixture)

from planner import BatchResult, plan_batch
from planner.batch_result import BATCH_FORMAT_VERSION, BatchRow
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import read_result_json


def test_the_result_writes_csv_and_json_with_nan_as_empty_and_null(cost, tmp_path):
    res = plan_batch(cost, [*PAIRS[:2], [*ON_WALL, *EAST]])
    assert [p.name for p in res.write(tmp_path)] == ["batch.csv", "batch.json"]
    with open(tmp_path / "batch.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["status"] for r in rows] == ["exact", "exact", "error"]
    assert float(rows[0]["energy_j"]) == res.rows[0].energy_j  # repr round-trips
    assert rows[2]["energy_j"] == "" and rows[2]["error"].startswith("BlockedPositionError")
    data = json.loads((tmp_path / "batch.json").read_text())
    assert data["format_version"] == BATCH_FORMAT_VERSION and data["n_pairs"] == 3
    assert data["counts"]["error"] == 1 and data["rows"][2]["energy_j"] is None
    assert data["rows"][0]["energy_saved_pct"] == pytest.approx(res.rows[0].energy_saved_pct)
    assert res.to_dict()["median_energy_saved_pct"] == pytest.approx(res.median_saving_pct())
    assert read_result_json(tmp_path / "batch.json", "batch", BATCH_FORMAT_VERSION) == data  # through the one result codec


def test_rows_and_results_check_themselves():
    with pytest.raises(InvalidParameterError, match="status must be one of"):
        BatchRow("a", 0.0, 0.0, 1.0, 1.0, "done")
    with pytest.raises(InvalidParameterError, match="error text exactly when its status is 'error'"):
        BatchRow("a", 0.0, 0.0, 1.0, 1.0, "error")
    with pytest.raises(InvalidParameterError, match="rows must be BatchRow"):
        BatchResult(({"name": "a"},), "lattice", "in process", 1, 1.0)
    res = BatchResult((BatchRow("a", 0.0, 0.0, 1.0, 1.0, "infeasible"),), "lattice", "in process", 1, 0.0)
    assert math.isnan(res.routes_per_s) and math.isnan(res.median_saving_pct())
    with pytest.raises(InvalidParameterError, match="column must be one of"):
        res.column("energy")


def test_the_table_shows_missing_numbers_as_dashes_and_cuts_long_batches(cost):
    res = plan_batch(cost, [*PAIRS, [*ON_WALL, *EAST]])
    lines = res.table(max_rows=4).splitlines()
    assert lines[0].split() == ["pair", "status", "energy", "Wh", "length", "m", "time", "s", "saved", "%"]
    assert lines[2].split()[:2] == ["0", "exact"] and float(lines[2].split()[2]) == round(res.rows[0].energy_wh, 2)
    assert lines[-1] == "... 1 more rows"
    assert res.table().splitlines()[-1].split() == ["4", "error", "-", "-", "-", "-"]


def test_the_figure_draws_each_pairs_energy_beside_the_shortest_routes(cost, tmp_path):
    from matplotlib.figure import Figure

    res = plan_batch(cost, [*PAIRS[:2], [*ON_WALL, *EAST]])
    ax = Figure().subplots()
    assert res.plot(ax=ax, title="mine") is ax
    assert [b.get_height() for b in ax.patches] == pytest.approx([r.energy_wh for r in res.rows[:2]])
    assert [t.get_text() for t in ax.get_xticklabels()] == [r.name for r in res.rows]
    lines = {line.get_label(): line for line in ax.lines}
    assert list(lines["shortest-distance route"].get_ydata())[:2] == pytest.approx(
        [r.shortest_energy_j / 3600.0 for r in res.rows[:2]])
    assert list(lines["no route"].get_xdata()) == [2] and ax.get_title() == "mine"
    png = res.plot(tmp_path / "batch.png")
    assert png == tmp_path / "batch.png" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(InvalidParameterError, match="not both"):
        res.plot(tmp_path / "other.png", ax=ax)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes"):
        res.plot(ax=Figure().subplots(1, 2))
