"""Tests of benchmarks/house_numbers.py: the counts issue 34 tracks, read from the source."""

from __future__ import annotations

import json

import house_numbers


def test_the_counts_name_what_they_count(tmp_path):
    numbers = house_numbers.house_numbers()
    assert numbers["library_lines"] > 10_000
    assert "planner/tours/result.py:TourResult" in numbers["result_class_names"]
    assert numbers["result_classes"] == len(numbers["result_class_names"])
    widest = numbers["widest"]
    assert widest and all(w["parameters"] > 8 for w in widest)
    assert [w["parameters"] for w in widest] == sorted((w["parameters"] for w in widest), reverse=True)
    assert not any(w["function"].startswith("planner/kernels/") for w in widest)  # the kernels are counted apart
    assert house_numbers.main(["--out", str(tmp_path / "h.json")]) == 0
    assert json.loads((tmp_path / "h.json").read_text())["result_classes"] == numbers["result_classes"]


def test_parameters_count_without_self():
    import ast

    tree = ast.parse("class A:\n    def f(self, a, b, *c, d, **e): pass\ndef g(a, /, b): pass\n")
    fns = {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    assert house_numbers._n_params(fns["f"]) == 5 and house_numbers._n_params(fns["g"]) == 2
