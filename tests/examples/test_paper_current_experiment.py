"""Runs examples/paper_current_experiment.py --quick and checks its Table I."""

from __future__ import annotations

import contextlib
import io
import runpy
from pathlib import Path

import numpy as np
import pytest

from energy import TruthSimulator, charge_mah, robot_preset
from energy.sim import PAPER_GROUNDS, PAPER_VARIATION

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "paper_current_experiment.py"


@pytest.fixture(scope="module")
def example() -> dict:
    return runpy.run_path(str(SCRIPT), run_name="paper_current_experiment")


@pytest.fixture(scope="module")
def figures_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("figures")


@pytest.fixture(scope="module")
def quick_run(example: dict, figures_dir: Path) -> tuple[list, str]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        tables = example["main"](["--quick", "--seed", "0", "--out", str(figures_dir)])
    return tables, buf.getvalue()


def test_writes_the_papers_figures(quick_run: tuple[list, str], figures_dir: Path) -> None:
    expected = {f"current_{g}.png" for g in PAPER_GROUNDS} | {"spectra.png"}
    assert {p.name for p in figures_dir.iterdir()} == expected
    for name in expected:
        assert (figures_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_prints_table_one_for_each_ground(quick_run: tuple[list, str]) -> None:
    tables, out = quick_run
    assert [t.ground for t in tables] == list(PAPER_GROUNDS)
    for name in PAPER_GROUNDS:
        assert f"Ground: {name}" in out
    assert out.count("  whole ") == 3
    assert "right truth" in out and "left truth" in out and "error %" in out


def test_sections_add_up_and_errors_are_the_papers_rate(example: dict, quick_run: tuple[list, str]) -> None:
    tables, _ = quick_run
    for t in tables:
        assert len(t.section_bounds_s) == example["N_SECTIONS"]
        for rows in (t.right, t.left):
            assert len(rows) == example["N_SECTIONS"] + 1
            sections, whole = rows[:-1], rows[-1]
            assert sum(r.truth_mah for r in sections) == pytest.approx(whole.truth_mah, rel=1e-9)
            assert sum(r.estimate_mah for r in sections) == pytest.approx(whole.estimate_mah, rel=1e-9)
            for r in rows:
                assert r.error_pct == pytest.approx(abs(r.estimate_mah - r.truth_mah) / r.truth_mah * 100)
        spans = np.diff(np.array(t.section_bounds_s), axis=1).ravel()
        assert spans == pytest.approx(example["QUICK_DURATION_S"] / example["N_SECTIONS"], abs=0.011)


def test_truth_column_is_the_test_runs_charge(example: dict, quick_run: tuple[list, str]) -> None:
    tables, _ = quick_run
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=example["NOISE"], variation=PAPER_VARIATION)
    train, test = example["simulate_runs"](sim, "snow_over_concrete", example["QUICK_DURATION_S"], 0)
    assert not np.array_equal(train.current_right_a, test.current_right_a)  # run 2 is a new run
    assert np.array_equal(train.v_mps, test.v_mps)  # ... of the same command pattern
    table = tables[2]
    assert table.right[-1].truth_mah == pytest.approx(charge_mah(test.time_s, test.current_right_a), rel=1e-12)
    assert table.left[-1].truth_mah == pytest.approx(charge_mah(test.time_s, test.current_left_a), rel=1e-12)


def test_estimates_are_in_the_right_range(quick_run: tuple[list, str]) -> None:
    tables, _ = quick_run
    for t in tables:
        # a tiny model trained for seconds: loose bounds that still catch unit or side mix-ups
        assert t.right[-1].error_pct < 60 and t.left[-1].error_pct < 60
        assert max(t.baseline_error_pct) < 30
