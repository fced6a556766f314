"""Tests of planner.batch.plan_batch_on_map: a batch on a map priced by a CostSpec, summarised and written."""

from __future__ import annotations

import json

import pytest

from planner import BatchPairs, BatchResult, plan_batch
from planner.batch import plan_batch_on_map
from planner.cost_spec import CostSpec
from terrain import InvalidParameterError

PAIRS = [[5.0, 5.0, 35.0, 5.0], [35.0, 5.0, 5.0, 5.0], [5.0, 5.0, 20.5, 5.5]]  # the last one ends in the wall


@pytest.fixture
def report(wall_map) -> BatchResult:
    return plan_batch_on_map(wall_map, BatchPairs.from_array(PAIRS, ["there", "back", "wall"]),
                             map_label="wall")


def test_the_pairs_are_those_of_plan_batch_on_the_priced_map(report, wall_map):
    assert isinstance(report, BatchResult) and len(report) == 3 and report.map_label == "wall"
    same = plan_batch(CostSpec().build(wall_map), PAIRS)
    assert [r.energy_j for r in report.rows[:2]] == [r.energy_j for r in same.rows[:2]]
    assert [r.status for r in report.rows] == ["exact", "exact", "error"] and not report.all_found
    assert report.where == "in process"


def test_the_summary_is_the_header_the_table_and_the_totals(report):
    assert report.header() == "map: wall  40 x 40 cells of 1 m; 3 pairs; planner lattice"
    assert report.summary() == "\n".join([report.header(), report.table(), "", report.totals()])
    assert "3 pairs (2 exact, 1 error) planned with lattice" in report.totals()


def test_write_gives_csv_and_json(report, tmp_path):
    csv_path, json_path = report.write(tmp_path / "out")
    assert csv_path.name == "batch.csv" and json_path.name == "batch.json"
    assert len(json.loads(json_path.read_text())["rows"]) == 3


def test_a_model_prices_the_map(corridor_map, known_model):
    report = plan_batch_on_map(corridor_map, [[2.5, 7.5, 27.5, 7.5]], pricing=CostSpec(model=known_model()))
    assert report.all_found and report.rows[0].status == "exact"


def test_bad_slope_is_refused(wall_map):
    with pytest.raises(InvalidParameterError, match="max_slope_deg"):
        plan_batch_on_map(wall_map, PAIRS, pricing=CostSpec(max_slope_deg=-1.0))
