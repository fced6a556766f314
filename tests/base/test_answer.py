"""Tests of terrawatt_base.answer: an answer's files and figures written into a folder, its tables, its numbers."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from terrawatt_base.answer import fmt_fixed, markdown_table, write_answer
from terrawatt_base.errors import FigureWarning, UnknownNameError


def _text(text: str):
    def write(path: Path) -> Path:
        path.write_text(text)
        return path
    return write


def _broken(path: Path) -> Path:
    raise ValueError("bad axes")


def test_fmt_fixed_rounds_and_leaves_a_gap_for_what_is_not_a_number():
    assert fmt_fixed(1.25) == "1.2" and fmt_fixed(-0.006, 2) == "-0.01"
    assert [fmt_fixed(x) for x in (math.nan, math.inf, None)] == ["–"] * 3
    assert fmt_fixed(math.nan, 2, missing="-") == "-"


def test_markdown_table_aligns_numbers_right_after_the_text_columns():
    assert markdown_table(["a", "b", "c"], [[1, "x", 2.5]], left=2) == [
        "| a | b | c |", "|---|---|---:|", "| 1 | x | 2.5 |"]
    assert markdown_table(["a", "b"], []) == ["| a | b |", "|---|---|"]


def test_write_answer_writes_files_in_order_then_figures(tmp_path):
    out = tmp_path / "new" / "folder"
    written = write_answer(out, {"b.json": _text("{}"), "skip.txt": lambda p: None, "a.md": _text("# a")},
                           {"z.png": _text("png")})
    assert [p.name for p in written] == ["b.json", "a.md", "z.png"]
    assert not (out / "skip.txt").exists() and (out / "a.md").read_text() == "# a"


def test_a_figure_that_fails_warns_and_the_files_stand_or_raises(tmp_path):
    with pytest.warns(FigureWarning, match=r"could not draw .*f.png: ValueError: bad axes"):
        written = write_answer(tmp_path, {"a.json": _text("{}")}, {"f.png": _broken, "g.png": _text("g")})
    assert [p.name for p in written] == ["a.json", "g.png"]
    with pytest.raises(ValueError, match="bad axes"):
        write_answer(tmp_path, {}, {"f.png": _broken}, on_figure_error="raise")


def test_a_bad_on_figure_error_is_refused_before_anything_is_written(tmp_path):
    with pytest.raises(UnknownNameError, match="on_figure_error"):
        write_answer(tmp_path / "out", {"a.json": _text("{}")}, on_figure_error="ignore")
    assert not (tmp_path / "out").exists()
